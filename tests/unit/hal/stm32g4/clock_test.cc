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
constexpr Address kPwrCr1 = 0x40007000, kPwrCr5 = 0x40007080, kPwrSr2 = 0x40007014;
constexpr Address kFlashAcr = 0x40022000;
constexpr std::uint32_t kHseon = 1u << 16, kHserdy = 1u << 17;
constexpr std::uint32_t kPllon = 1u << 24, kPllrdy = 1u << 25;

// The hardware's answers: ready bits follow their enables, SWS follows SW.
void ModelRcc(ScriptedSpace& s, bool hse_starts = true) {
  s.memory[kPwrCr1] = 0x200u;                 // VOS = 01, Range 1 (reset value)
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
  // ACR read back before HSE. VOSF is not waited for: the range stays Range 1, only
  // R1MODE changes (ST's HAL, HAL_PWREx_ControlVoltageScaling, waits for VOSF only
  // when it changes CR1.VOS).
  bool vosf_read = false, acr_read = false;
  for (long i = boost; i < hse; ++i) {
    const auto& a = s.log[static_cast<std::size_t>(i)];
    vosf_read |= !a.write && a.address == kPwrSr2;
    acr_read |= !a.write && a.address == kFlashAcr && i > latency;
  }
  EXPECT_FALSE(vosf_read);
  EXPECT_TRUE(acr_read);
  EXPECT_TRUE(s.WritesTo(kPwrCr1).empty());
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

TEST(Stm32g4Clock, FromRange2TheRangeChangesFirstAndVosfIsWaitedFor) {
  ScriptedSpace s;
  ModelRcc(s);
  s.memory[kPwrCr1] = 0x400u;  // VOS = 10, Range 2
  ASSERT_EQ(ConfigureClocks(), ClockResult::kOk);
  const long range1 =
      s.FirstWrite(kPwrCr1, [](std::uint32_t v) { return ((v >> 9) & 3u) == 0b01u; });
  ASSERT_GE(range1, 0);
  long vosf = -1;
  for (std::size_t i = static_cast<std::size_t>(range1); i < s.log.size(); ++i) {
    if (!s.log[i].write && s.log[i].address == kPwrSr2) {
      vosf = static_cast<long>(i);
      break;
    }
  }
  ASSERT_GE(vosf, 0) << "VOSF read after the range change";
  EXPECT_LT(vosf, s.FirstWrite(kRccCr, HasBits(kHseon)));
}

// 5 ms of the cycle counter at HCLK = 8 MHz (HSI16 / 2 during the wait): 40,000 cycles.
TEST(Stm32g4Clock, NoCrystalStopsBeforeTheSwitchAfterFiveMilliseconds) {
  ScriptedSpace s;
  ModelRcc(s, /*hse_starts=*/false);
  static int serviced = 0;
  serviced = 0;
  EXPECT_EQ(ConfigureClocks([] { ++serviced; }), ClockResult::kHseTimeout);
  EXPECT_LT(s.FirstWrite(kRccPllcfgr, testing::Any()), 0);
  EXPECT_EQ(s.Peek(kRccCfgr) & 3u, 0b01u);        // still HSI16
  EXPECT_EQ((s.Peek(kRccCfgr) >> 4) & 0xFu, 0u);  // at AHB /1
  EXPECT_NE(s.Peek(kRccCr) & kHseon, 0u) << "left on: a late crystal shows later";
  // The wait's length on the cycle counter: from the HSEON write to the last HSERDY read.
  const long hse = s.FirstWrite(kRccCr, HasBits(kHseon));
  ASSERT_GE(hse, 0);
  std::uint32_t first = 0, last = 0;
  bool seen = false;
  for (std::size_t i = static_cast<std::size_t>(hse); i < s.log.size(); ++i) {
    if (!s.log[i].write && s.log[i].address == testing::kCyccntAddress) {
      if (!seen) first = s.log[i].value;
      last = s.log[i].value;
      seen = true;
    }
  }
  ASSERT_TRUE(seen);
  EXPECT_GE(last - first, 40'000u);
  EXPECT_LE(last - first, 40'000u + 2 * s.cycles_per_read);
  EXPECT_GT(serviced, 100) << "the watchdog is fed while it waits";
}

// Without the crystal, the PLL from HSI16: PLLSRC = 10, PLLM = 4 − 1, the same N/R/Q,
// so SYSCLK is 16 / 4 × 85 / 2 = 170 MHz and PLLQ 85 MHz.
TEST(Stm32g4Clock, FromHsiTheSamePllRunsFromHsi16) {
  ScriptedSpace s;
  ModelRcc(s, /*hse_starts=*/false);
  ASSERT_EQ(ConfigureClocks(), ClockResult::kHseTimeout);
  const std::size_t before = s.log.size();
  ASSERT_EQ(ConfigureClocksFromHsi(), ClockResult::kOk);
  const long pllcfg = s.FirstWrite(
      kRccPllcfgr,
      Equals(0x2u | (3u << 4) | (85u << 8) | (1u << 24) | (1u << 21) | (1u << 20)),
      static_cast<long>(before));
  ASSERT_GE(pllcfg, 0);
  const long switch_pll = s.FirstWrite(
      kRccCfgr,
      [](std::uint32_t v) { return (v & 3u) == 3u && ((v >> 4) & 0xF) == 0b1000; },
      pllcfg);
  ASSERT_GE(switch_pll, 0);
  EXPECT_EQ((s.Peek(kRccCfgr) >> 4) & 0xFu, 0u);  // AHB /1 at the end
  EXPECT_EQ(ActiveClockSource(), ClockSource::kHsiPll);
  EXPECT_FALSE(HseReady());
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
