// The bootloader's side of the STM32G474: what its image does to the chip besides the
// drivers (hal/stm32g4) — the pins and clocks it uses, the reset flags it reads without
// clearing them, the board's instance, a millisecond clock — and the return of all of
// it to the reset state before the hand-over. Register accesses through the drivers'
// mmio layer, so the host runs it against the chip's register models.
//
// What the bootloader touches, and in what state the application finds it:
//   GPIOA (PA11/PA12 FDCAN1), GPIOB (PB10, the bridge's enable), FDCAN1, its kernel
//     clock (CCIPR.FDCANSEL): reset (RCC reset bits) and their clocks off — as at reset;
//   the clock tree (HSE, PLL at 170 MHz): SYSCLK back on HSI16, AHB /1, PLL off and
//     PLLCFGR at its reset value, HSE off — as at reset (it hands over only when the
//     crystal ran: g474_bootloader.h);
//   NVIC: every interrupt disabled and every pending one cleared; PRIMASK cleared at the
//     jump (mjc/boot/jump.h) — as at reset;
// and left as they are, documented:
//   the IWDG keeps running (nothing stops it but a reset: RM0440 §42.3) with the
//     100 ms the application programs itself; the application refreshes it well
//     within that (its main() starts it anew a few ms after its reset handler);
//   FLASH_ACR: 4 wait states, prefetch, caches on (valid at any HCLK up to 170 MHz;
//     the application's clock bring-up sets the same);
//   PWR: the clock enable and Range 1 boost (R1MODE = 0), which the application's
//     bring-up selects anyway; the DWT cycle counter runs;
//   the FPU's access (CPACR) enabled, as the application's first step does.
#pragma once

#include <cstdint>

#include "mjc/protocol/messages.h"

namespace mjc::boot::g474 {

// The last reset, from RCC_CSR's flags, which stay set for the application (it reports
// its own reset). A power-on clears SFTRSTF.
struct ResetFlags {
  bool software = false;  // SFTRSTF: a software reset (AIRCR.SYSRESETREQ)
  protocol::ResetCause cause = protocol::ResetCause::kUnknown;
  std::uint8_t flags = 0;  // RCC_CSR bits 24..31 (OBL .. LPWR at 1..7) for ChipInfo
};
ResetFlags PeekResetFlags();
// Clears them (RCC_CSR.RMVF): once the bootloader stays, the application will not run
// before the next reset, whose own flags must not be mixed with these.
void ClearResetFlags();

// The bridge's enable line (PB10, GPIOB's clock on) an output driven low: the
// bootloader's first act. The board's pull-down holds it low before (reset) and after
// (the hand-over returns PB10 to its reset state). TIM1 is never clocked and its pins
// stay in their reset state (analog), so the bootloader cannot drive the motor.
void HoldBridgeOff();

// FDCAN1's pins (PA11 RX, PA12 TX, AF9) and clocks (kernel clock PLLQ, 85 MHz, once
// the clock tree runs: from the crystal, or from HSI16 when it failed). Nothing else is
// clocked.
void EnableCanPeripherals();

// The raw FLASH_OPTR (RM0440 FLASH_OPTR: the option bytes as loaded at reset).
std::uint32_t OptionBytes();

// The physical board: the chip's 96-bit unique id (RM0440 §48.1, at 0x1FFF7590), its
// three words XOR-folded to 16 bits — the fold the application reports in its BoardInfo,
// so a host sees one instance whichever image answers.
std::uint16_t BoardInstance();

// Milliseconds since the first call, from the DWT cycle counter at `cycles_per_ms`; exact
// across the counter's wrap as long as Now() is called at least once per wrap less a
// millisecond (25 s at 170 MHz; the bootloader's loop calls it every few µs, its
// longest flash work lasts ~60 ms).
class MsClock {
 public:
  explicit MsClock(std::uint32_t cycles_per_ms) : cycles_per_ms_(cycles_per_ms) {}
  std::uint32_t Now();

 private:
  std::uint32_t cycles_per_ms_;
  bool started_ = false;
  std::uint32_t last_ = 0;
  std::uint32_t ms_ = 0;
  std::uint32_t remainder_ = 0;
};

// Everything above back to its reset state (see the list at the top). Interrupts must
// be disabled (PRIMASK set), as they are in the bootloader.
void ReleasePeripherals();

}  // namespace mjc::boot::g474
