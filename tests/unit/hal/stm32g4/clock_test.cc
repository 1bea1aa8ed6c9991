// The clock bring-up's order and values against RM0440: PWR Range 1 boost and the
// flash latency before any frequency increase, HSE, PLL (configured while off), AHB /2
// around the switch, ≥ 1 µs, then /1.
#include "hal/stm32g4/clock.h"

#include <gtest/gtest.h>

#include "scripted_space.h"

namespace mjc::stm32g4 {
namespace {

using testing::Equals;
using testing::HasBits;
using testing::LacksBits;
using testing::ScriptedSpace;

// Addresses and bits from RM0440 §7.4 (RCC), §6.4 (PWR), §5.7 (FLASH).
constexpr Address kRccCr = 0x40021000, kRccCfgr = 0x40021008, kRccPllcfgr = 0x4002100C;
constexpr Address kRccApb1enr1 = 0x40021058, kRccApb2enr = 0x40021060;
constexpr Address kRccAhb2enr = 0x4002104C, kRccCcipr = 0x40021088;
constexpr Address kPwrCr5 = 0x40007080, kPwrSr2 = 0x40007014;
constexpr Address kFlashAcr = 0x40022000;
constexpr std::uint32_t kHseon = 1u << 16, kHserdy = 1u << 17;
constexpr std::uint32_t kPllon = 1u << 24, kPllrdy = 1u << 25;

// The hardware's answers: ready bits follow their enables, SWS follows SW.
void ModelRcc(ScriptedSpace& s, bool hse_starts = true) {
  s.memory[kPwrCr5] = 1u << 8;                // R1MODE reset value 1
  s.memory[kRccCfgr] = 0b01;                  // HSI16 selected after reset
  s.memory[kRccCr] = (1u << 8) | (1u << 10);  // HSION, HSIRDY
  s.after_write = [&s, hse_starts](Address a, std::uint32_t v) {
    if (a == kRccCr) {
      std::uint32_t cr = v & ~(kHserdy | kPllrdy);
      if ((v & kHseon) && hse_starts) cr |= kHserdy;
      if (v & kPllon) cr |= kPllrdy;
      s.memory[kRccCr] = cr;
    }
    if (a == kRccCfgr) s.memory[kRccCfgr] = (v & ~0xCu) | ((v & 0x3u) << 2);
  };
}

TEST(Stm32g4Clock, BringsUp170MHzInTheManualsOrder) {
  ScriptedSpace s;
  ModelRcc(s);
  ASSERT_EQ(ConfigureClocks(), ClockResult::kOk);

  const long pwren = s.FirstWrite(kRccApb1enr1, HasBits(1u << 28));
  const long boost = s.FirstWrite(kPwrCr5, LacksBits(1u << 8));
  // ACR: LATENCY = 4, PRFTEN (8), ICEN (9), DCEN (10).
  const long latency = s.FirstWrite(kFlashAcr, Equals(0x704));
  const long hse = s.FirstWrite(kRccCr, HasBits(kHseon));
  // PLLCFGR: PLLSRC = HSE (11), PLLM = 6 − 1 at 7:4, PLLN = 85 at 14:8, PLLR = /2 (00)
  // at 26:25 with PLLREN (24), PLLQ = /4 (01) at 22:21 with PLLQEN (20).
  const long pllcfg = s.FirstWrite(
      kRccPllcfgr,
      Equals(0x3u | (5u << 4) | (85u << 8) | (1u << 24) | (1u << 21) | (1u << 20)));
  const long pll_on = s.FirstWrite(kRccCr, HasBits(kPllon));
  // HPRE = 1000 (/2) first, while SW still selects HSI16 (RM0440 §6.1.5 step 1); later
  // SW = 11 (PLL) with HPRE still /2.
  const long ahb_div2 =
      s.FirstWrite(kRccCfgr, [](std::uint32_t v) { return ((v >> 4) & 0xF) == 0b1000; });
  const long switch_pll = s.FirstWrite(kRccCfgr, [](std::uint32_t v) {
    return (v & 3u) == 3u && ((v >> 4) & 0xF) == 0b1000;
  });
  const long ahb_div1 = s.FirstWrite(
      kRccCfgr, [](std::uint32_t v) { return (v & 3u) == 3u && ((v >> 4) & 0xF) == 0; },
      switch_pll);
  for (long i :
       {pwren, boost, latency, hse, pllcfg, pll_on, ahb_div2, switch_pll, ahb_div1}) {
    ASSERT_GE(i, 0);
  }
  EXPECT_LT(pwren, boost);
  EXPECT_LT(ahb_div2, boost);
  EXPECT_EQ(s.log[static_cast<std::size_t>(ahb_div2)].value & 3u, 0b01u);  // on HSI16
  EXPECT_LT(boost, latency);
  EXPECT_LT(latency, hse);
  EXPECT_LT(hse, pllcfg);
  EXPECT_LT(pllcfg, pll_on);
  EXPECT_LT(pll_on, switch_pll);
  EXPECT_LT(switch_pll, ahb_div1);
  // The PLL was off (PLLON cleared) when PLLCFGR was written.
  EXPECT_GE(s.FirstWrite(kRccCr, LacksBits(kPllon)), 0);
  EXPECT_LT(s.FirstWrite(kRccCr, LacksBits(kPllon)), pllcfg);
  // The regulator was waited for, and ACR read back, before HSE.
  bool vosf_read = false, acr_read = false;
  for (long i = boost; i < hse; ++i) {
    const auto& a = s.log[static_cast<std::size_t>(i)];
    vosf_read |= !a.write && a.address == kPwrSr2;
    acr_read |= !a.write && a.address == kFlashAcr && i > latency;
  }
  EXPECT_TRUE(vosf_read);
  EXPECT_TRUE(acr_read);
  // ≥ 1 µs between the switch and HPRE = /1: the cycle counter was read past 170 cycles.
  std::uint32_t first = 0, last = 0;
  bool seen = false;
  for (long i = switch_pll; i < ahb_div1; ++i) {
    const auto& a = s.log[static_cast<std::size_t>(i)];
    if (!a.write && a.address == testing::kCyccntAddress) {
      if (!seen) first = a.value;
      last = a.value;
      seen = true;
    }
  }
  ASSERT_TRUE(seen);
  EXPECT_GE(last - first, 170u);
  // APB1 and APB2 /1 at the end: PPRE1 (10:8) = PPRE2 (13:11) = 0.
  EXPECT_EQ((s.Peek(kRccCfgr) >> 8) & 0x3Fu, 0u);
}

TEST(Stm32g4Clock, NoCrystalStopsBeforeTheSwitch) {
  ScriptedSpace s;
  ModelRcc(s, /*hse_starts=*/false);
  EXPECT_EQ(ConfigureClocks(), ClockResult::kHseTimeout);
  EXPECT_LT(s.FirstWrite(kRccPllcfgr, testing::Any()), 0);
  EXPECT_EQ(s.Peek(kRccCfgr) & 3u, 0b01u);        // still HSI16
  EXPECT_EQ((s.Peek(kRccCfgr) >> 4) & 0xFu, 0u);  // at AHB /1
}

TEST(Stm32g4Clock, PeripheralClocksAndFdcanKernelClock) {
  ScriptedSpace s;
  EnablePeripheralClocks();
  EXPECT_EQ(s.Peek(kRccAhb2enr) & 0x7u, 0x7u);  // GPIOA/B/C
  EXPECT_EQ(s.Peek(kRccApb2enr),
            (1u << 0) | (1u << 11) | (1u << 12));           // SYSCFG TIM1 SPI1
  EXPECT_EQ(s.Peek(kRccApb1enr1), (1u << 1) | (1u << 25));  // TIM3, FDCAN
  EXPECT_EQ((s.Peek(kRccCcipr) >> 24) & 3u, 0b01u);         // FDCANSEL = PLLQ
  // The kernel clock is chosen before FDCAN's clock is enabled.
  EXPECT_LT(s.FirstWrite(kRccCcipr, testing::Any()),
            s.FirstWrite(kRccApb1enr1, HasBits(1u << 25)));
}

}  // namespace
}  // namespace mjc::stm32g4
