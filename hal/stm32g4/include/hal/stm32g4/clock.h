// The joint board's clock tree (RM0440 §7, RCC; §6.1.5, dynamic voltage scaling; §5.3.3,
// flash read latency) and the peripheral clocks the drivers need.
//
//   HSE 24 MHz crystal ─/M=6─▶ 4 MHz ─×N=85─▶ VCO 340 MHz ─┬─/R=2─▶ SYSCLK 170 MHz
//                                                          └─/Q=4─▶ PLLQ 85 MHz ─▶ FDCAN
//   AHB /1: HCLK 170 MHz.  APB1 /1, APB2 /1: PCLK1 = PCLK2 = 170 MHz (the G474's APB
//   maximum is the system's, 170 MHz), so TIM1 and TIM3 count at 170 MHz (the timer
//   clock doubles only when its APB prescaler is not 1) and SPI1 runs from 170 MHz.
//
// PLL limits (RM0440 §7.2.4, as ST's LL clock code also checks them): VCO input 2.66-16
// MHz (4 MHz here), VCO output 64-344 MHz (340 MHz), PLLR output ≤ 170 MHz. FDCAN from
// PLLQ rather than PCLK1 so that its bit timing does not change if the APB prescaler
// ever does: 85 MHz gives integer bit times at 1 and 5 Mbit/s (fdcan.h).
//
// Without the crystal (ConfigureClocksFromHsi, after ConfigureClocks reported
// kHseTimeout) the same PLL runs from HSI16:
//
//   HSI16 16 MHz ─/M=4─▶ 4 MHz ─×N=85─▶ VCO 340 MHz ─┬─/R=2─▶ SYSCLK 170 MHz
//                                                   └─/Q=4─▶ PLLQ 85 MHz ─▶ FDCAN
//
// Every frequency above is the same, so the tick, the timers and FDCAN's bit timing
// need no second set of numbers; only their accuracy is HSI16's (DS12288, as recalled:
// ±1 % over 0-85 °C after the factory trim, wider over the full range) instead of the
// crystal's tens of ppm. hal/README.md ("Clock") says what that allows on the bus.
#pragma once

#include <cstdint>

namespace mjc::stm32g4 {

// The board's crystal.
inline constexpr std::uint32_t kHseHz = 24'000'000;
inline constexpr std::uint32_t kPllM = 6;
inline constexpr std::uint32_t kPllN = 85;
inline constexpr std::uint32_t kPllR = 2;
inline constexpr std::uint32_t kPllQ = 4;
inline constexpr std::uint32_t kVcoInputHz = kHseHz / kPllM;
inline constexpr std::uint32_t kVcoHz = kVcoInputHz * kPllN;
inline constexpr std::uint32_t kSysclkHz = kVcoHz / kPllR;
inline constexpr std::uint32_t kHclkHz = kSysclkHz;
inline constexpr std::uint32_t kPclk1Hz = kHclkHz;
inline constexpr std::uint32_t kPclk2Hz = kHclkHz;
inline constexpr std::uint32_t kTimerClockHz = kPclk2Hz;  // TIM1 (APB2), TIM3 (APB1)
inline constexpr std::uint32_t kFdcanKernelHz = kVcoHz / kPllQ;
static_assert(kHseHz % kPllM == 0 && kVcoInputHz >= 2'660'000 &&
              kVcoInputHz <= 16'000'000);
static_assert(kVcoHz >= 64'000'000 && kVcoHz <= 344'000'000);
static_assert(kSysclkHz == 170'000'000 && kFdcanKernelHz == 85'000'000);
// The fallback's PLL input divider: HSI16 / 4 gives the same 4 MHz VCO input.
inline constexpr std::uint32_t kHsiHz = 16'000'000;
inline constexpr std::uint32_t kPllMHsi = 4;
static_assert(kHsiHz / kPllMHsi == kVcoInputHz && kHsiHz % kPllMHsi == 0);

// How long ConfigureClocks waits for HSERDY. DS12288 gives tSU(HSE) ≈ 2 ms for a
// crystal (from HSEON to a stable clock); 5 ms leaves the part's spread and a cold
// start a margin, and is short beside the 100 ms watchdog the application inherits from
// the bootloader (which the wait also refreshes). A crystal slower than this is a faulty
// crystal: the board then runs from HSI16 and says so (hal/README.md, "Clock").
inline constexpr std::uint32_t kHseTimeoutMs = 5;
// The wait is timed with the DWT cycle counter, which counts HCLK: HSI16 through the
// AHB /2 step of the bring-up, 8 MHz (clock.cc, step 2).
inline constexpr std::uint32_t kHclkDuringHseWaitHz = kHsiHz / 2;
inline constexpr std::uint32_t kHseTimeoutCycles =
    kHseTimeoutMs * (kHclkDuringHseWaitHz / 1000);

// Flash wait states at 170 MHz in Range 1 boost: RM0440 §5.3.3, Table "Number of wait
// states according to CPU clock (HCLK) frequency": 4 WS up to 170 MHz.
inline constexpr std::uint32_t kFlashWaitStates = 4;

// Stable codes; a bring-up that fails leaves the chip on HSI16 (16 MHz) or on the last
// step it completed, and the board must not run the motor.
enum class ClockResult : std::uint8_t {
  kOk = 0,
  kVoltageTimeout = 1,  // the regulator did not settle (PWR_SR2.VOSF)
  kFlashLatency = 2,    // FLASH_ACR did not take the new latency
  kHseTimeout = 3,      // no crystal (RCC_CR.HSERDY)
  kPllTimeout = 4,      // PLL did not lock (RCC_CR.PLLRDY)
  kSwitchTimeout = 5,   // SYSCLK did not switch to the PLL (RCC_CFGR.SWS)
};

// Called during every wait of the bring-up: the application refreshes the watchdog it
// inherited from the bootloader (stm32g4::RefreshWatchdog); null: nothing.
using ClockService = void (*)();

// From reset (HSI16, Range 1 normal, 0 WS) to 170 MHz from the HSE, in the order
// RM0440 §6.1.5 and §7 require (each step is commented in clock.cc). Also starts the
// DWT cycle counter, which the HSE's timeout and the 1 µs intermediate step are timed
// with. HSERDY is waited for kHseTimeoutMs at most; on kHseTimeout the chip is left on
// HSI16 at AHB /1 with HSEON still set (a late crystal shows as HSERDY later on).
ClockResult ConfigureClocks(ClockService service = nullptr);

// After ConfigureClocks failed (or from reset): the same 170 MHz and 85 MHz PLLQ from
// HSI16 through the PLL (M = 4), in the same order. HSEON is left as it is.
ClockResult ConfigureClocksFromHsi(ClockService service = nullptr);

// What SYSCLK runs from, read from RCC (CFGR.SWS and PLLCFGR.PLLSRC). Stable codes.
enum class ClockSource : std::uint8_t {
  kHsi16 = 0,   // HSI16 alone (the reset state; a bring-up that failed altogether)
  kHsePll = 1,  // the crystal through the PLL: as designed
  kHsiPll = 2,  // HSI16 through the PLL: the crystal did not start
  kOther = 3,   // HSE alone, or a PLL from no source
};
ClockSource ActiveClockSource();
// RCC_CR.HSERDY: the crystal runs (true also when it started after the timeout).
bool HseReady();

// Clocks of the peripherals this board uses: GPIOA/B/C, TIM1, SPI1, SYSCFG (APB2),
// TIM3, FDCAN (APB1), and FDCAN's kernel clock = PLLQ (RCC_CCIPR.FDCANSEL = 01).
void EnablePeripheralClocks();

}  // namespace mjc::stm32g4
