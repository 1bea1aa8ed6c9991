// What protects the bridge and the board at first bring-up, with the image's own
// drivers on the STM32G474 register models (sim_host/g474):
//
//  - The duty clamp: at a full command in either direction, each leg's low side still
//    conducts the gate driver's minimum on-time every PWM period (board::
//    kBridgeLowSideMinNs), measured on the timer model's complementary output waves at
//    the clock tree the start-up code brings up (170 MHz). Without the clamp (margin 0,
//    CCR = ARR) the same measurement gives no on-time at all.
//  - A debugger's halt: the virtual board, from its own start-up, sweeping (the bridge
//    driven), is halted for a second (VirtualChip::Halt, as a probe's halt request):
//    the bridge's high sides are off and its low sides on throughout (TIM1 frozen with
//    its outputs at their idle levels), no watchdog reset comes, and once resumed the
//    firmware ticks on. Without the start-up's DBGMCU freeze bits the watchdog resets
//    the chip 100 ms into the halt, after TIM1 had kept switching at the last duty.
//  - The stack guards' MPU programming (EnableStackGuards) on the Cortex model: the
//    model sees no RAM access, so the guard is put over a register block it does see;
//    accesses there are denied, everywhere else the default map holds (PRIVDEFENA).
//    The real overflow is proven on QEMU's Cortex-M4 (tests/target/stack_guard).
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "board.h"
#include "hal/stm32g4/bridge_pwm.h"
#include "hal/stm32g4/clock.h"
#include "hal/stm32g4/gpio.h"
#include "hal/stm32g4/mmio.h"
#include "hal/stm32g4/mpu.h"
#include "hal/stm32g4/regs/tim1.h"
#include "mjc/g474board/virtual_board.h"
#include "mjc/g474model/virtual_chip.h"
#include "mjc/host/board_client.h"
#include "mjc/host/can_link.h"
#include "mjc/plant/params.h"
#include "virtual_board_rig.h"

namespace {

using namespace mjc;
using g474model::Pin;
using g474model::PinId;
using g474model::VirtualChip;

// The board's bridge pins (pins.h): CH1 PA8, CH1N PB13, CH2 PA9, CH2N PB14.
const g474model::PinId kLegAHigh = Pin('A', 8), kLegALow = Pin('B', 13);
const g474model::PinId kLegBHigh = Pin('A', 9), kLegBLow = Pin('B', 14);

// The chip at the board's clocks with its pins configured, TIM1 left to the test.
class BridgeOnModel : public testing::Test {
 protected:
  void SetUp() override {
    stm32g4::BindRegisterSpace(&chip_);
    ASSERT_EQ(stm32g4::ConfigureClocks(), stm32g4::ClockResult::kOk);
    stm32g4::EnablePeripheralClocks();
    for (const stm32g4::PinConfig& pin : board::kPins) stm32g4::ConfigurePin(pin);
  }
  void TearDown() override { stm32g4::BindRegisterSpace(nullptr); }

  // Past the next update event, where the preloaded compare values take effect.
  void ToNextUpdate() {
    const g474model::Picoseconds next = chip_.tim1().NextUpdate();
    ASSERT_NE(next, g474model::kNever);
    chip_.AdvanceTo(next + 1000);
  }

  // A pin's on-time per PWM period, in seconds: its wave's high fraction times the
  // period the model's counter runs (2 × ARR counts of the timer clock, centre-aligned).
  double OnTime(g474model::PinId pin) {
    const g474model::OutputWave w = chip_.PinWave(pin);
    EXPECT_TRUE(w.driven);
    const double arr = stm32g4::Read32(stm32g4::tim1::kBase + stm32g4::tim1::kArr);
    return w.duty * 2 * arr / chip_.tim1().kernel_hz();
  }

  static g474model::ChipConfig BoardCrystal() {
    g474model::ChipConfig config;
    config.rcc.hse_hz = 24e6;  // the board's crystal (stm32g4/clock.h: PLLM = 6)
    return config;
  }

  VirtualChip chip_{BoardCrystal()};
};

TEST_F(BridgeOnModel, FullCommandLeavesEachLowSideItsMinimumOnTime) {
  using Pwm = board::JointIo::Pwm;
  const double minimum = board::kBridgeLowSideMinNs * 1e-9;
  Pwm::Init();
  ASSERT_NEAR(chip_.tim1().kernel_hz(), 170e6, 1);
  for (const std::int16_t raw : {std::int16_t{32767}, std::int16_t{-32768}}) {
    Pwm::ISR_SetDuty(Duty::FromRaw(raw));
    ToNextUpdate();
    EXPECT_GE(OnTime(kLegALow), minimum) << raw;
    EXPECT_GE(OnTime(kLegBLow), minimum) << raw;
    // Each high side is on for the rest of the period but the dead times, and the mean
    // drive is the clamp's: (ARR − 2N)/ARR less nothing (dead times cancel by leg).
    const g474model::BridgeDrive d =
        chip_.HBridge(kLegAHigh, kLegBHigh, g474model::Pin('B', 10));
    EXPECT_NEAR(std::abs(d.duty), 1 - 2.0 * 107 / 4250, 1e-9) << raw;
  }
  // Mid-range commands are left as they were: d = 0.5 → 3188/1062, no clamp near.
  Pwm::ISR_SetDuty(Duty::FromRaw(16384));
  ToNextUpdate();
  EXPECT_EQ(stm32g4::Read32(stm32g4::tim1::kBase + stm32g4::tim1::kCcr1), 3188u);
}

TEST_F(BridgeOnModel, WithoutTheMarginAFullCommandStarvesTheLowSide) {
  // The control: the same measurement on the unclamped mapping sees the silicon's
  // problem (CCR = ARR: OCxREF low for one count, shorter than the dead time).
  using Unclamped = stm32g4::Stm32g4BridgePwm<stm32g4::tim1::kBase, 0>;
  Unclamped::Init();
  Unclamped::ISR_SetDuty(Duty::FromRaw(32767));
  ToNextUpdate();
  EXPECT_EQ(OnTime(kLegALow), 0.0);
  EXPECT_LT(OnTime(kLegALow), board::kBridgeLowSideMinNs * 1e-9);
}

TEST_F(BridgeOnModel, StackGuardProgrammingDeniesOnlyTheGuard) {
  const std::uint32_t guard = stm32g4::tim1::kBase;  // 1 KB, aligned to its size
  const stm32g4::GuardRegion guards[] = {{guard, 1024}};
  ASSERT_TRUE(stm32g4::EnableStackGuards(guards));
  auto mpu_reports = [&] {
    std::size_t n = 0;
    for (const auto& v : chip_.violations().entries()) n += v.source == "MPU";
    return n;
  };
  ASSERT_EQ(mpu_reports(), 0u);
  (void)stm32g4::Read32(guard + 0x2C);
  (void)stm32g4::Read32(guard + 0x3FC);
  stm32g4::Write32(guard, 1);
  EXPECT_EQ(mpu_reports(), 3u);
  (void)stm32g4::Read32(guard + 0x400);  // the block above (SPI1): the default map
  (void)stm32g4::Read32(0x40021000u);    // RCC
  EXPECT_EQ(mpu_reports(), 3u);
  // Malformed guards are refused before the MPU is touched.
  const stm32g4::GuardRegion unaligned[] = {{guard + 0x100, 1024}};
  EXPECT_FALSE(stm32g4::EnableStackGuards(unaligned));
  const stm32g4::GuardRegion too_many[9] = {};
  EXPECT_FALSE(stm32g4::EnableStackGuards(too_many));
}

TEST(VirtualBoardDebugHalt, FreezesTheWatchdogAndTakesTheBridgeToIdle) {
  auto bus = host::InProcessBus::Create();
  auto board_link = bus->Connect();
  auto host_link = bus->Connect();
  g474board::VirtualBoardConfig config;
  config.plant = plant::LoadPlantParams("default");
  config.speed = 0;  // as fast as the machine runs it: no wall time in any verdict
  config.log = nullptr;
  g474board::VirtualBoard board(config, board_link.get());
  board.Resume();
  host::BoardClient client(host_link.get(), 1);
  std::string why;
  host::WaitEnd end{};
  ASSERT_TRUE(client.Await([&] { return client.status().heard; }, {}, &end, &why)) << why;
  // The calibration sweep drives the motor: the bridge enabled at a varying duty.
  ASSERT_EQ(client.Start(g474board::rig::PaperSweep(), 1000, &why),
            protocol::CommandOutcomeCode::kAccepted)
      << why;
  const PinId in1 = Pin('A', 8), in2 = Pin('A', 9), enable = Pin('B', 10);
  g474model::BridgeDrive before;
  for (int i = 0; i < 100; ++i) {
    board.RunUntil(board.now_s() + 0.02);
    before = board.chip().HBridge(in1, in2, enable);
    if (before.enabled && std::abs(before.duty) > 0.05) break;
  }
  ASSERT_TRUE(before.enabled && std::abs(before.duty) > 0.05)
      << "the sweep never drove the bridge";
  const int resets = board.Summary().resets;
  const std::uint32_t tick = board.firmware()->app().last().telemetry.tick;

  struct Seen {
    g474model::BridgeDrive drive;
    g474model::OutputWave high_a, low_a, high_b, low_b;
    bool timer_stopped = false;
  } seen;
  bool halt_ended = false;
  constexpr g474model::Picoseconds kMs = 1'000'000'000;
  board.Post([&] {
    g474model::VirtualChip& chip = board.chip();
    chip.Halt();
    chip.AdvanceTo(chip.now() + 50 * kMs);
    seen = {
        chip.HBridge(in1, in2, enable), chip.PinWave(in1),
        chip.PinWave(Pin('B', 13)),     chip.PinWave(in2),
        chip.PinWave(Pin('B', 14)),     chip.tim1().NextUpdate() == g474model::kNever};
    chip.AdvanceTo(chip.now() + 950 * kMs);  // a second halted: ten watchdog periods
    chip.Resume();
    halt_ended = true;
  });
  board.RunUntil(board.now_s() + 1.2);

  EXPECT_EQ(board.Summary().resets, resets) << "a watchdog reset during the halt";
  EXPECT_TRUE(halt_ended);
  EXPECT_TRUE(seen.timer_stopped) << "TIM1 went on counting while halted";
  // High sides off, low sides on (OIS1/2 = 0, OIS1N/2N = 1 with OSSI = 1): no drive.
  EXPECT_TRUE(seen.high_a.driven && seen.low_a.driven && seen.high_b.driven &&
              seen.low_b.driven);
  EXPECT_EQ(seen.high_a.duty, 0.0);
  EXPECT_EQ(seen.high_b.duty, 0.0);
  EXPECT_EQ(seen.low_a.duty, 1.0);
  EXPECT_EQ(seen.low_b.duty, 1.0);
  EXPECT_EQ(seen.drive.duty, 0.0);
  // Running again: the firmware's tick goes on (0.2 s of the 1.2 s were not halted).
  ASSERT_NE(board.firmware(), nullptr);
  EXPECT_GT(board.firmware()->app().last().telemetry.tick, tick + 1500);
  board.Stop();
  EXPECT_EQ(board.Summary().resets, resets);
  std::string violations;
  for (const auto& v : board.violations()) violations += v.source + ": " + v.what + "\n";
  EXPECT_TRUE(violations.empty()) << violations;
}

}  // namespace
