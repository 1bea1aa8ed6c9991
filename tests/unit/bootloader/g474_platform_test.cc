// The bootloader's STM32G474 side on the chip's register models (sim_host/g474): the
// pins it drives (the bridge's enable low, FDCAN1's), the reset flags it reads without
// clearing, the board's instance, its millisecond clock, and the hand-over state —
// every register it used as a reset leaves it, so that the application's own
// start-up (clock bring-up, peripheral clocks, FDCAN) runs on it without breaking a
// rule of the reference manual.
#include "mjc/boot/g474_platform.h"

#include <gtest/gtest.h>

#include <array>
#include <vector>

#include "hal/stm32g4/clock.h"
#include "hal/stm32g4/fdcan.h"
#include "hal/stm32g4/gpio.h"
#include "hal/stm32g4/nvic.h"
#include "hal/stm32g4/poll.h"
#include "hal/stm32g4/regs/fdcan.h"
#include "hal/stm32g4/regs/gpio.h"
#include "hal/stm32g4/regs/rcc.h"
#include "hal/stm32g4/watchdog.h"
#include "mjc/g474model/virtual_chip.h"

namespace {

using namespace mjc;
using g474model::VirtualChip;
using stm32g4::Address;
using stm32g4::Read32;

class Bound {
 public:
  explicit Bound(VirtualChip* chip) { stm32g4::BindRegisterSpace(chip); }
  ~Bound() { stm32g4::BindRegisterSpace(nullptr); }
};

constexpr std::uint32_t kRcc = stm32g4::rcc::kBase;
constexpr std::uint32_t kPwren = 1u << 28;

// The registers the bootloader touches, as they read now.
std::vector<std::uint32_t> Snapshot() {
  namespace rcc = stm32g4::rcc;
  namespace gpio = stm32g4::gpio;
  std::vector<std::uint32_t> v = {
      Read32(kRcc + rcc::kCr),
      Read32(kRcc + rcc::kCfgr),
      Read32(kRcc + rcc::kPllcfgr),
      Read32(kRcc + rcc::kAhb2enr),
      Read32(kRcc + rcc::kApb1enr1) & ~kPwren,  // PWREN: left on (documented)
      Read32(kRcc + rcc::kApb2enr),
      Read32(kRcc + rcc::kCcipr),
      Read32(kRcc + rcc::kAhb2rstr),
      Read32(kRcc + rcc::kApb1rstr1),
  };
  for (const stm32g4::Port port : {stm32g4::Port::kA, stm32g4::Port::kB}) {
    const Address base = stm32g4::PortAddress(port);
    // Read with the port's clock on (a block with its clock off reads 0).
    const Address en = kRcc + rcc::kAhb2enr;
    const std::uint32_t was = Read32(en);
    stm32g4::Write32(en,
                     was | rcc::ahb2enr::kGpioaen.Bit() | rcc::ahb2enr::kGpioben.Bit());
    for (const std::uint32_t reg :
         {gpio::kModer, gpio::kOtyper, gpio::kOspeedr, gpio::kPupdr, gpio::kAfrh}) {
      v.push_back(Read32(base + reg));
    }
    stm32g4::Write32(en, was);
  }
  for (std::uint32_t i = 0; i < 4; ++i) {
    v.push_back(Read32(stm32g4::nvic::kBase + stm32g4::nvic::kIser0 + 4 * i));
  }
  return v;
}

// The joint board: its 24 MHz crystal (hal/stm32g4/clock.h).
g474model::ChipConfig Board() {
  g474model::ChipConfig c;
  c.rcc.hse_hz = stm32g4::kHseHz;
  return c;
}

std::array<stm32g4::CanFilter, 3> Filters() {
  return {{{0x393, 0x7FF}, {0x3A3, 0x7FF}, {0x3C3, 0x7FF}}};
}

TEST(G474Platform, HandsOverInTheResetStateAndTheApplicationStartsOnIt) {
  VirtualChip chip(Board());
  Bound bound(&chip);
  const auto at_reset = Snapshot();
  // The bootloader's run: its clocks and pins, FDCAN up, interrupts masked.
  stm32g4::DisableInterrupts();
  boot::g474::HoldBridgeOff();
  ASSERT_EQ(stm32g4::ConfigureClocks(), stm32g4::ClockResult::kOk);
  boot::g474::EnableCanPeripherals();
  stm32g4::Stm32g4Fdcan can;
  ASSERT_EQ(can.Init(Filters()), stm32g4::FdcanResult::kOk);
  EXPECT_EQ(chip.fdcan1().nominal_bitrate(), 1e6);
  EXPECT_NE(Snapshot(), at_reset);
  boot::g474::ReleasePeripherals();
  EXPECT_EQ(Snapshot(), at_reset);
  EXPECT_EQ(chip.rcc().sysclk_hz(), 16e6);
  // The application's start-up, as from a reset.
  stm32g4::EnableInterrupts();
  EXPECT_EQ(stm32g4::ConfigureClocks(), stm32g4::ClockResult::kOk);
  stm32g4::EnablePeripheralClocks();
  stm32g4::Stm32g4Fdcan app_can;
  EXPECT_EQ(app_can.Init(Filters()), stm32g4::FdcanResult::kOk);
  EXPECT_EQ(chip.rcc().sysclk_hz(), 170e6);
  EXPECT_TRUE(chip.violations().empty()) << chip.violations().ToString();
}

TEST(G474Platform, TheBridgeEnableIsDrivenLowAndTim1NeverRuns) {
  VirtualChip chip;
  Bound bound(&chip);
  boot::g474::HoldBridgeOff();
  EXPECT_EQ(chip.gpio('B').mode(10), g474model::PinMode::kOutput);
  EXPECT_EQ(chip.gpio('B').Level(10), false);
  EXPECT_EQ(chip.gpio('A').mode(11), g474model::PinMode::kAnalog) << "nothing else yet";
  boot::g474::EnableCanPeripherals();
  EXPECT_FALSE(chip.gpio('B').odr(10));
  EXPECT_EQ(chip.gpio('B').Level(10), false);
  EXPECT_EQ(chip.gpio('A').mode(11), g474model::PinMode::kAlternate);
  EXPECT_EQ(chip.gpio('A').af(12), 9u);
  // TIM1 and its pins untouched: clock off, PA8/PA9/PB13/PB14 in their reset mode.
  EXPECT_EQ(Read32(kRcc + stm32g4::rcc::kApb2enr), 0u);
  EXPECT_EQ(chip.gpio('A').mode(8), g474model::PinMode::kAnalog);
  EXPECT_EQ(chip.gpio('A').mode(9), g474model::PinMode::kAnalog);
  EXPECT_EQ(chip.gpio('B').mode(13), g474model::PinMode::kAnalog);
  EXPECT_EQ(chip.gpio('B').mode(14), g474model::PinMode::kAnalog);
  EXPECT_TRUE(chip.violations().empty()) << chip.violations().ToString();
}

TEST(G474Platform, ResetFlagsAreReadNotCleared) {
  VirtualChip chip;
  chip.SetResetHandler([](g474model::ResetCause) {});
  Bound bound(&chip);
  auto flags = boot::g474::PeekResetFlags();
  EXPECT_FALSE(flags.software);
  EXPECT_EQ(flags.cause, protocol::ResetCause::kPowerOn);
  stm32g4::RequestSystemReset();
  flags = boot::g474::PeekResetFlags();
  EXPECT_TRUE(flags.software);
  EXPECT_EQ(flags.cause, protocol::ResetCause::kSoftware);
  EXPECT_TRUE(boot::g474::PeekResetFlags().software) << "still there for the application";
  EXPECT_EQ(stm32g4::TakeResetCause(), stm32g4::ResetCause::kSoftware);
  EXPECT_FALSE(boot::g474::PeekResetFlags().software);
  stm32g4::RequestSystemReset();
  boot::g474::ClearResetFlags();
  EXPECT_EQ(boot::g474::PeekResetFlags().cause, protocol::ResetCause::kUnknown);
}

TEST(G474Platform, InstanceIsTheUniqueIdFolded) {
  VirtualChip chip;
  Bound bound(&chip);
  const g474model::FlashConfig config;
  const std::uint32_t folded = config.uid[0] ^ config.uid[1] ^ config.uid[2];
  EXPECT_EQ(boot::g474::BoardInstance(),
            static_cast<std::uint16_t>(folded ^ (folded >> 16)));
}

TEST(G474Platform, TheMillisecondClockKeepsTimeAcrossTheCountersWrap) {
  VirtualChip chip;
  Bound bound(&chip);
  stm32g4::EnableCycleCounter();
  boot::g474::MsClock clock(16'000);  // HSI16: 16,000 cycles a millisecond
  EXPECT_EQ(clock.Now(), 0u);
  std::uint64_t spent = 0;
  for (int i = 0; i < 400; ++i) {
    const std::uint64_t n = 12'345'678;  // ~0.77 s a step, past 2^32 cycles after 348
    chip.SpendCycles(n);
    spent += n;
    // The clock reads the counter a few cycles after SpendCycles: at most 1 ms behind.
    const std::uint32_t now = clock.Now();
    ASSERT_LE(now, spent / 16'000 + 1);
    ASSERT_GE(now + 1, spent / 16'000);
  }
  EXPECT_GT(spent, std::uint64_t{1} << 32);
}

}  // namespace
