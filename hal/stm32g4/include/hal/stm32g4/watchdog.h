// The independent watchdog (RM0440 §42, IWDG) and the cause of the last reset (RCC_CSR,
// RM0440 §7.4, RCC_CSR: the reset flags).
//
// Timeout: 100 ms (LSI ≈ 32 kHz / 32 → 1 kHz, reload 99 → 100 counts). Long enough for
// the slowest thing the main loop does between two refreshes — a calibration page
// erase, ≤ 40 ms — with margin for the LSI's spread; short enough that a hung CPU (whose
// PWM would keep running) is reset within 0.1 s, after which the pins are in analog mode
// (no driver, no pull; GPIOx_MODER resets to all ones on most pins) and the board's
// pull-downs hold the bridge's enable line low. Once started the watchdog
// cannot be stopped except by a reset.
#pragma once

#include <cstdint>

#include "hal/stm32g4/mmio.h"
#include "hal/stm32g4/regs/iwdg.h"

namespace mjc::stm32g4 {

inline constexpr std::uint32_t kLsiHz = 32'000;
inline constexpr std::uint32_t kWatchdogPrescalerCode = 3;  // /4 × 2^3 = /32
inline constexpr std::uint32_t kWatchdogReload = 99;
inline constexpr std::uint32_t kWatchdogTimeoutMs =
    (4u << kWatchdogPrescalerCode) * (kWatchdogReload + 1) * 1000u / kLsiHz;
static_assert(kWatchdogTimeoutMs == 100);

// Stable codes.
enum class WatchdogResult : std::uint8_t {
  kOk = 0,
  kTimeout = 1,  // PR/RLR did not reach the LSI domain (the LSI did not start)
};

// Starts the watchdog with the timeout above (RM0440 §42.3, "Software watchdog mode":
// KR = 0xCCCC starts it and the LSI, 0x5555 unlocks PR/RLR, write them, wait until
// SR.PVU = SR.RVU = 0, then KR = 0xAAAA reloads).
WatchdogResult StartWatchdog();

// Reloads the counter: the main loop calls it only when the control tick has also made
// progress since the last call, so a hung tick or a hung main loop both reset the chip.
inline void RefreshWatchdog() { Write32(iwdg::kBase + iwdg::kKr, iwdg::kr::kReload); }

// Why the chip last reset. Stable codes, reported after boot. The NRST pin flag is set
// by every reset (the reset circuit drives the pin), so the most specific cause wins.
enum class ResetCause : std::uint8_t {
  kUnknown = 0,
  kPowerOn = 1,              // power-on / brown-out (BORRSTF)
  kPin = 2,                  // the NRST pin alone (PINRSTF)
  kSoftware = 3,             // AIRCR.SYSRESETREQ (SFTRSTF)
  kIndependentWatchdog = 4,  // IWDGRSTF
  kWindowWatchdog = 5,       // WWDGRSTF
  kLowPower = 6,             // illegal Stop/Standby entry (LPWRRSTF)
  kOptionByteLoader = 7,     // OBL_LAUNCH (OBLRSTF)
};

// Reads RCC_CSR's reset flags and clears them (RMVF) so the next boot reports only its
// own reset.
ResetCause TakeResetCause();

}  // namespace mjc::stm32g4
