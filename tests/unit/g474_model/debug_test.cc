// A debugger's halt against RM0440's DBGMCU freeze bits (APB1FZR1.DBG_IWDG_STOP bit 12,
// DBG_TIM3_STOP bit 1; APB2FZR.DBG_TIM1_STOP bit 11; CMSIS stm32g474xx.h) and the TIM1
// "Debug mode" paragraph: without the bits the watchdog resets a halted chip and TIM1
// keeps switching at its last duty; with them both stop, TIM1's outputs at their
// MOE-cleared levels. The registers survive a system reset, not a power cut.
#include <gtest/gtest.h>

#include <optional>

#include "mjc/g474model/virtual_chip.h"

namespace {

using namespace mjc::g474model;

constexpr std::uint32_t kDbgmcu = 0xE0042000, kApb1fzr1 = kDbgmcu + 0x08,
                        kApb2fzr = kDbgmcu + 0x10;
constexpr std::uint32_t kIwdg = 0x40003000, kT1 = 0x40012C00, kT3 = 0x40000400;
constexpr Picoseconds kMs = 1'000'000'000;

// The IWDG at about 100 ms (LSI 32 kHz / 32, reload 99: 100 counter ticks), as RM0440's
// configuration sequence has it: start, unlock, PR, RLR, wait for the updates, reload.
void StartWatchdog(VirtualChip& c) {
  c.Write(kIwdg + 0x00, 0xCCCC, 4);
  c.Write(kIwdg + 0x00, 0x5555, 4);
  c.Write(kIwdg + 0x04, 3, 4);
  c.Write(kIwdg + 0x08, 99, 4);
  while (c.Read(kIwdg + 0x0C, 4) != 0) {
  }
  c.Write(kIwdg + 0x00, 0xAAAA, 4);
}

// Advances a halted chip; the reset it took, if any.
std::optional<ResetCause> AdvanceHalted(VirtualChip& c, Picoseconds dt) {
  try {
    c.AdvanceTo(c.now() + dt);
  } catch (const ChipReset& r) {
    return r.cause;
  }
  return std::nullopt;
}

TEST(G474Debug, HaltWithoutFreezeLetsTheWatchdogResetTheChip) {
  VirtualChip c;
  StartWatchdog(c);
  c.Halt();
  const auto reset = AdvanceHalted(c, 200 * kMs);
  ASSERT_TRUE(reset.has_value()) << "a halted core does not stop the IWDG by itself";
  EXPECT_EQ(*reset, ResetCause::kIwdg);
  EXPECT_FALSE(c.halted()) << "the reset ends the halt";
}

TEST(G474Debug, IwdgStopFreezesTheCounterWhileHaltedOnly) {
  VirtualChip c;
  c.Write(kApb1fzr1, 1u << 12, 4);  // DBG_IWDG_STOP
  EXPECT_EQ(c.Read(kApb1fzr1, 4), 1u << 12);
  StartWatchdog(c);
  c.AdvanceTo(c.now() + 40 * kMs);  // 40 of its 100 ms spent before the halt
  c.iwdg().Advance(c.now());
  const std::uint32_t at_halt = c.iwdg().counter();
  c.Halt();
  EXPECT_FALSE(AdvanceHalted(c, 1000 * kMs).has_value());
  c.iwdg().Advance(c.now());
  EXPECT_EQ(c.iwdg().counter(), at_halt);
  c.Resume();
  // Running again, it goes on from where it stopped: ~60 ms left, not 100.
  EXPECT_FALSE(AdvanceHalted(c, 50 * kMs).has_value());
  const auto reset = AdvanceHalted(c, 20 * kMs);
  ASSERT_TRUE(reset.has_value());
  EXPECT_EQ(*reset, ResetCause::kIwdg);
}

// TIM1 CH1/CH1N complementary at 75 % (edge-aligned, 16 MHz, 20 kHz), OSSI = 1 with
// the low side's idle level high (OIS1N), MOE set, the update interrupt enabled.
void StartPwm(VirtualChip& c, bool ossi) {
  c.Write(0x40021060, 1u << 11, 4);  // TIM1EN
  c.Write(kT1 + 0x2C, 799, 4);
  c.Write(kT1 + 0x18, (6u << 4) | (1u << 3), 4);
  c.Write(kT1 + 0x34, 600, 4);
  c.Write(kT1 + 0x04, 1u << 9, 4);  // CR2.OIS1N
  c.Write(kT1 + 0x20, 1u | (1u << 2), 4);
  c.Write(kT1 + 0x44, (1u << 15) | (ossi ? 1u << 10 : 0u) | 8u, 4);  // MOE, DTG 8
  c.Write(kT1 + 0x14, 1, 4);
  c.Write(kT1 + 0x10, 0, 4);
  c.Write(kT1 + 0x0C, 1, 4);  // UIE
  c.Write(kT1 + 0x00, 1, 4);  // CEN
}

TEST(G474Debug, HaltWithoutFreezeKeepsTim1SwitchingAtItsLastDuty) {
  VirtualChip c;
  StartPwm(c, true);
  int ticks = 0;
  c.SetHandler(irq::kTim1Up, [&] {
    ++ticks;
    c.Write(kT1 + 0x10, 0, 4);
  });
  c.Write(0xE000E100, 1u << irq::kTim1Up, 4);
  c.AdvanceTo(c.now() + kMs);
  ASSERT_GT(ticks, 10);
  c.Halt();
  const int before = ticks;
  const std::uint32_t count = (c.tim1().Advance(c.now()), c.tim1().counter());
  c.AdvanceTo(c.now() + 10 * kMs + 3'000'000);  // + 48 counts
  c.tim1().Advance(c.now());
  EXPECT_NE(c.tim1().counter(), count) << "the counter runs on";
  EXPECT_NEAR(c.tim1().Wave(1, false).duty, 0.75 - 0.5 / 50, 1e-9);
  EXPECT_EQ(ticks, before) << "a halted core takes no interrupt";
  c.Resume();
  EXPECT_EQ(ticks, before + 1) << "the pending update is taken once the core runs";
}

TEST(G474Debug, Tim1StopDisablesTheOutputsAsMoeClearedAndStopsTheCounter) {
  for (const bool ossi : {true, false}) {
    VirtualChip c;
    c.Write(kApb2fzr, 1u << 11, 4);  // DBG_TIM1_STOP
    StartPwm(c, ossi);
    c.AdvanceTo(c.now() + kMs);
    c.Halt();
    c.tim1().Advance(c.now());
    const std::uint32_t count = c.tim1().counter();
    EXPECT_EQ(c.tim1().NextUpdate(), kNever) << "no update event while frozen";
    c.AdvanceTo(c.now() + 10 * kMs + 3'000'000);  // + 48 counts
    c.tim1().Advance(c.now());
    EXPECT_EQ(c.tim1().counter(), count);
    const OutputWave high = c.tim1().Wave(1, false), low = c.tim1().Wave(1, true);
    if (ossi) {
      // Idle levels: OIS1 = 0 (high side off), OIS1N = 1 (low side on).
      EXPECT_TRUE(high.driven && low.driven);
      EXPECT_EQ(high.duty, 0.0);
      EXPECT_EQ(low.duty, 1.0);
    } else {
      EXPECT_FALSE(high.driven) << "OSSI = 0: released to the GPIO (Hi-Z)";
      EXPECT_FALSE(low.driven);
    }
    EXPECT_TRUE(c.Read(kT1 + 0x44, 4) & (1u << 15)) << "MOE itself is kept";
    c.Resume();
    EXPECT_NEAR(c.tim1().Wave(1, false).duty, 0.75 - 0.5 / 50, 1e-9) << ossi;
    EXPECT_NE(c.tim1().NextUpdate(), kNever);
  }
}

TEST(G474Debug, Tim3StopLosesEncoderEdgesWhileHalted) {
  for (const bool stop : {false, true}) {
    VirtualChip c;
    if (stop) c.Write(kApb1fzr1, 1u << 1, 4);  // DBG_TIM3_STOP
    c.Write(0x40021058, 2u, 4);                // TIM3EN
    c.Write(0x4002104C, 1u, 4);                // GPIOAEN
    c.AttachEncoder(Pin('A', 6), Pin('A', 4));
    c.Write(0x48000000,
            (c.Read(0x48000000, 4) & ~((3u << 12) | (3u << 8))) | (2u << 12) | (2u << 8),
            4);
    c.Write(0x48000020, (2u << 24) | (2u << 16), 4);  // PA6, PA4 AF2
    c.Write(kT3 + 0x18, 1u | (1u << 8), 4);
    c.Write(kT3 + 0x08, 3u, 4);  // x4
    c.Write(kT3 + 0x2C, 0xFFFF, 4);
    c.Write(kT3 + 0x00, 1, 4);
    c.MoveEncoder(100);
    c.Halt();
    c.MoveEncoder(140);  // the motor turned by hand during the halt
    c.Resume();
    c.MoveEncoder(150);
    EXPECT_EQ(c.Read(kT3 + 0x24, 4), stop ? 110u : 150u);
  }
}

TEST(G474Debug, FreezeBitsSurviveASystemResetButNotAPowerCut) {
  VirtualChip c;
  c.SetResetHandler([](ResetCause) {});
  c.Write(kApb1fzr1, (1u << 12) | (1u << 1), 4);
  c.Write(kApb2fzr, 1u << 11, 4);
  c.Write(0xE000ED0C, (0x05FAu << 16) | (1u << 2), 4);  // AIRCR.SYSRESETREQ
  EXPECT_EQ(c.resets(), 1);
  EXPECT_EQ(c.Read(kApb1fzr1, 4), (1u << 12) | (1u << 1));
  EXPECT_EQ(c.Read(kApb2fzr, 4), 1u << 11);
  c.PowerCut();
  EXPECT_EQ(c.Read(kApb1fzr1, 4), 0u);
  EXPECT_EQ(c.Read(kApb2fzr, 4), 0u);
  EXPECT_EQ(c.Read(kDbgmcu, 4) & 0xFFFu, 0x469u);  // DEV_ID: STM32G47x/G48x
}

}  // namespace
