// RCC/PWR/IWDG against RM0440: ready flags after start-up delays, the frequency
// bookkeeping, the ordering rules (wait states before the clock, boost above 150 MHz),
// clock gating, reset-cause flags, the watchdog's expiry time.
#include <gtest/gtest.h>

#include "mjc/g474model/virtual_chip.h"

namespace {

using namespace mjc::g474model;

constexpr std::uint32_t kRcc = 0x40021000, kPwr = 0x40007000, kFlash = 0x40022000;

// The bring-up to 170 MHz from an 8 MHz HSE in the order the manual asks for.
void BringUp170(VirtualChip& c, bool latency_first = true, bool boost = true) {
  c.Write(kRcc + 0x58, c.Read(kRcc + 0x58, 4) | (1u << 28), 4);  // PWREN
  if (boost) c.Write(kPwr + 0x80, 0, 4);                         // R1MODE = 0
  if (latency_first) c.Write(kFlash + 0x00, (c.Read(kFlash, 4) & ~0xFu) | 4u, 4);
  c.Write(kRcc + 0x00, c.Read(kRcc, 4) | (1u << 16), 4);  // HSEON
  while (!(c.Read(kRcc + 0x00, 4) & (1u << 17))) {
  }
  // PLLSRC = HSE, M = 2 (1), N = 85, R = 2 (0), PLLREN.
  c.Write(kRcc + 0x0C, 3u | (1u << 4) | (85u << 8) | (1u << 24), 4);
  c.Write(kRcc + 0x00, c.Read(kRcc, 4) | (1u << 24), 4);  // PLLON
  while (!(c.Read(kRcc + 0x00, 4) & (1u << 25))) {
  }
  c.Write(kRcc + 0x08, (8u << 4) | 3u, 4);  // HPRE /2, SW = PLL
  while (((c.Read(kRcc + 0x08, 4) >> 2) & 3u) != 3) {
  }
  c.AdvanceTo(c.now() + Microseconds(2));
  if (!latency_first) c.Write(kFlash + 0x00, (c.Read(kFlash, 4) & ~0xFu) | 4u, 4);
  c.Write(kRcc + 0x08, 3u | (4u << 8), 4);  // HPRE /1, PPRE1 /2
}

TEST(G474Rcc, ResetStateRunsOnHsi16) {
  VirtualChip c;
  EXPECT_EQ(c.Read(kRcc + 0x08, 4), 0x5u);
  EXPECT_EQ(c.Read(kRcc + 0x00, 4) & 0x500u, 0x500u);  // HSION, HSIRDY
  EXPECT_DOUBLE_EQ(c.rcc().sysclk_hz(), 16e6);
  EXPECT_EQ(c.Read(kRcc + 0x94, 4) & csr::kResetFlags, csr::kBorrstf | csr::kPinrstf);
}

TEST(G474Rcc, ReadyFlagsTakeTheirStartUpTime) {
  VirtualChip c;
  const Picoseconds t0 = c.now();
  c.Write(kRcc + 0x00, c.Read(kRcc, 4) | (1u << 16), 4);
  EXPECT_FALSE(c.Read(kRcc, 4) & (1u << 17));
  while (!(c.Read(kRcc, 4) & (1u << 17))) {
  }
  const Picoseconds waited = c.now() - t0;
  EXPECT_GE(waited, Microseconds(2000));
  EXPECT_LT(waited, Microseconds(2002));
}

// RM0440 RCC_CR.HSERDY: "set by hardware to indicate that the HSE oscillator is
// stable". A crystal that does not oscillate never sets it: the switch to it never
// completes (CFGR.SWS keeps HSI16) and a PLL fed by it never locks.
TEST(G474Rcc, AnHseThatNeverStartsNeverSetsHserdy) {
  VirtualChip c;
  c.rcc().SetHseStartup(kNever);
  c.Write(kRcc + 0x00, c.Read(kRcc, 4) | (1u << 16), 4);  // HSEON
  c.AdvanceTo(c.now() + Microseconds(1'000'000));
  EXPECT_EQ(c.Read(kRcc, 4) & (1u << 17), 0u) << "HSERDY after 1 s";
  c.Write(kRcc + 0x08, (c.Read(kRcc + 0x08, 4) & ~3u) | 2u, 4);  // SW = HSE
  c.AdvanceTo(c.now() + Microseconds(1000));
  EXPECT_EQ((c.Read(kRcc + 0x08, 4) >> 2) & 3u, 1u) << "SWS stays HSI16";
  EXPECT_DOUBLE_EQ(c.rcc().sysclk_hz(), 16e6);
  c.Write(kRcc + 0x08, (c.Read(kRcc + 0x08, 4) & ~3u) | 1u, 4);  // SW = HSI16 again
  // PLLSRC = HSE, M = /6, N = 85, PLLREN, then PLLON: it cannot lock.
  c.Write(kRcc + 0x0C, 3u | (5u << 4) | (85u << 8) | (1u << 24), 4);
  c.Write(kRcc + 0x00, c.Read(kRcc, 4) | (1u << 24), 4);
  c.AdvanceTo(c.now() + Microseconds(1000));
  EXPECT_EQ(c.Read(kRcc, 4) & (1u << 25), 0u) << "PLLRDY";
  EXPECT_FALSE(c.violations().empty()) << "PLLON with its source not ready";
}

// A crystal that starts late: HSERDY exactly when the world says, not at tSU(HSE).
TEST(G474Rcc, AnHseThatStartsLateSetsHserdyThen) {
  VirtualChip c;
  c.rcc().SetHseStartup(Microseconds(50'000));
  const Picoseconds t0 = c.now();
  c.Write(kRcc + 0x00, c.Read(kRcc, 4) | (1u << 16), 4);  // HSEON
  c.AdvanceTo(t0 + Microseconds(49'990));
  EXPECT_EQ(c.Read(kRcc, 4) & (1u << 17), 0u) << "HSERDY before 50 ms";
  while (!(c.Read(kRcc, 4) & (1u << 17))) {
  }
  EXPECT_GE(c.now() - t0, Microseconds(50'000));
  EXPECT_LT(c.now() - t0, Microseconds(50'002));
  // HSEON cleared and set again: the crystal starts anew, as late.
  c.Write(kRcc + 0x00, c.Read(kRcc, 4) & ~(1u << 16), 4);
  EXPECT_EQ(c.Read(kRcc, 4) & (1u << 17), 0u);
  const Picoseconds t1 = c.now();
  c.Write(kRcc + 0x00, c.Read(kRcc, 4) | (1u << 16), 4);
  c.AdvanceTo(t1 + Microseconds(2000));
  EXPECT_EQ(c.Read(kRcc, 4) & (1u << 17), 0u) << "not at the datasheet's 2 ms";
  EXPECT_TRUE(c.violations().empty()) << c.violations().ToString();
}

TEST(G474Rcc, BringUpGives170MHzAndTheBusClocks) {
  VirtualChip c;
  BringUp170(c);
  EXPECT_DOUBLE_EQ(c.rcc().sysclk_hz(), 170e6);
  EXPECT_DOUBLE_EQ(c.rcc().hclk_hz(), 170e6);
  EXPECT_DOUBLE_EQ(c.rcc().pclk1_hz(), 85e6);
  EXPECT_DOUBLE_EQ(c.rcc().tim_pclk1_hz(), 170e6);  // ×2: APB1 prescaler is not 1
  EXPECT_DOUBLE_EQ(c.rcc().pclk2_hz(), 170e6);
  EXPECT_TRUE(c.violations().empty()) << c.violations().ToString();
}

TEST(G474Rcc, LatencyRaisedAfterTheClockIsAViolation) {
  VirtualChip c;
  BringUp170(c, /*latency_first=*/false);
  EXPECT_TRUE(c.violations().Contains("FLASH", "wait states"))
      << c.violations().ToString();
}

TEST(G474Rcc, Above150MHzWithoutBoostIsAViolation) {
  VirtualChip c;
  BringUp170(c, true, /*boost=*/false);
  EXPECT_TRUE(c.violations().Contains("RCC", "Range 1 normal"))
      << c.violations().ToString();
}

TEST(G474Rcc, SwitchAbove80MHzNeedsTheAhbPrescalerStep) {
  VirtualChip c;
  c.Write(kRcc + 0x58, 1u << 28, 4);
  c.Write(kPwr + 0x80, 0, 4);
  c.Write(kFlash, 4, 4);
  c.Write(kRcc + 0x0C, 2u | (3u << 4) | (85u << 8) | (1u << 24), 4);  // HSI16/4*85/2
  c.Write(kRcc + 0x00, c.Read(kRcc, 4) | (1u << 24), 4);
  while (!(c.Read(kRcc, 4) & (1u << 25))) {
  }
  c.Write(kRcc + 0x08, 3u, 4);  // straight to 170 MHz at /1
  while (((c.Read(kRcc + 0x08, 4) >> 2) & 3u) != 3) {
  }
  EXPECT_TRUE(c.violations().Contains("RCC", "AHB prescaler at /1"));
}

TEST(G474Rcc, PeripheralWithClockOffIgnoresWritesAndReadsZero) {
  VirtualChip c;
  c.Write(0x40012C00 + 0x2C, 1000, 4);  // TIM1_ARR, clock off
  EXPECT_EQ(c.Read(0x40012C00 + 0x2C, 4), 0u);
  c.Write(kRcc + 0x60, 1u << 11, 4);                 // TIM1EN
  EXPECT_EQ(c.Read(0x40012C00 + 0x2C, 4), 0xFFFFu);  // reset value, the write was lost
}

TEST(G474Rcc, RmvfClearsTheResetFlags) {
  VirtualChip c;
  c.Write(kRcc + 0x94, 1u << 23, 4);
  EXPECT_EQ(c.Read(kRcc + 0x94, 4) & csr::kResetFlags, 0u);
}

TEST(G474Iwdg, ExpiresAfterFourTimesTwoToPrTimesRlPlusOneLsiCycles) {
  VirtualChip c;
  std::optional<ResetCause> cause;
  Picoseconds at = 0;
  c.SetResetHandler([&](ResetCause rc) {
    cause = rc;
    at = c.now();
  });
  c.Write(0x40003000, 0xCCCC, 4);
  c.Write(0x40003000, 0x5555, 4);
  c.Write(0x40003004, 1, 4);    // /8
  c.Write(0x40003008, 999, 4);  // 1000 ticks → 8000 LSI cycles = 250 ms + LSI start
  while (c.Read(0x4000300C, 4) != 0) {
  }
  c.Write(0x40003000, 0xAAAA, 4);
  const Picoseconds reload = c.now();
  c.AdvanceTo(reload + Microseconds(300000));
  ASSERT_TRUE(cause);
  EXPECT_EQ(*cause, ResetCause::kIwdg);
  // Counting started after the LSI's start-up (≤ 130 µs before the reload here).
  EXPECT_NEAR(static_cast<double>(at - reload) * 1e-12, 0.25, 0.0002);
  EXPECT_TRUE(c.Read(kRcc + 0x94, 4) & csr::kIwdgrstf);
}

TEST(G474Iwdg, ReloadInTimeKeepsTheChipAlive) {
  VirtualChip c;
  int resets = 0;
  c.SetResetHandler([&](ResetCause) { ++resets; });
  c.Write(0x40003000, 0xCCCC, 4);  // default: /4, RL 0xFFF → 512 ms
  for (int i = 0; i < 10; ++i) {
    c.AdvanceTo(c.now() + Microseconds(400000));
    c.Write(0x40003000, 0xAAAA, 4);
  }
  EXPECT_EQ(resets, 0);
}

}  // namespace
