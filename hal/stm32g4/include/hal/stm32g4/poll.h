// Bounded waits on a register (every wait in these drivers ends: a peripheral that
// never answers is reported, not waited on forever) and the DWT cycle counter.
#pragma once

#include <cstdint>

#include "hal/stm32g4/mmio.h"
#include "hal/stm32g4/regs/cortex_m4.h"

namespace mjc::stm32g4 {

// Reads `address` until (value & mask) == expected, at most `max_reads` times. True when
// it matched.
inline bool WaitFor(Address address, std::uint32_t mask, std::uint32_t expected,
                    std::uint32_t max_reads) {
  for (std::uint32_t i = 0; i < max_reads; ++i) {
    if ((Read32(address) & mask) == expected) return true;
  }
  return false;
}

// The DWT cycle counter (ARMv7-M C1.8): DEMCR.TRCENA powers the DWT, CTRL.CYCCNTENA
// starts the count. It counts core clock cycles and wraps every 2^32 (25 s at 170 MHz);
// differences of two reads are exact across one wrap.
inline void EnableCycleCounter() {
  const Address demcr = dcb::kBase + dcb::kDemcr;
  Write32(demcr, Read32(demcr) | dcb::demcr::kTrcena.Bit());
  const Address ctrl = dwt::kBase + dwt::kCtrl;
  Write32(ctrl, Read32(ctrl) | dwt::ctrl::kCyccntena.Bit());
}

// The counter of the DWT block at kDwt (a template argument, so that a tick-path driver
// can be built against a block placed in RAM, as its other registers).
template <Address kDwt = dwt::kBase>
struct CycleCounter {
  static std::uint32_t Now() { return Read32(kDwt + dwt::kCyccnt); }
  // Waits until `cycles` core cycles have passed since `since` (a Now()); returns at
  // once if they already have. For the short hold times a device's datasheet asks for.
  // Each pass of the loop takes at least one cycle, so `cycles` passes also end it: the
  // wait is never shorter than asked, and it ends even where the counter does not count
  // (halted by a debugger, or an emulator without a DWT).
  static void WaitSince(std::uint32_t since, std::uint32_t cycles) {
    for (std::uint32_t pass = 0; pass < cycles && Now() - since < cycles; ++pass) {
    }
  }
};

inline std::uint32_t CycleCount() { return CycleCounter<>::Now(); }
inline void WaitCyclesSince(std::uint32_t since, std::uint32_t cycles) {
  CycleCounter<>::WaitSince(since, cycles);
}

}  // namespace mjc::stm32g4
