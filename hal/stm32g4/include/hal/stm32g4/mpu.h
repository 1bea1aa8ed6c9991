// Stack guards on the Cortex-M4's memory protection unit (ARMv7-M B3.5): a no-access
// region at the bottom of each stack, so that a stack growing past its end faults at
// the first access there (MemManage, MMFSR.DACCVIOL or MSTKERR) instead of running on
// into what lies below. The address map itself promises no such fault: below SRAM1
// (0x2000_0000) lie the flash interface's system memory, OTP and option bytes
// (0x1FFF_0000 - 0x1FFF_7FFF and, on the dual-bank part, 0x1FFF_F800 up), and below CCM
// SRAM (0x1000_0000) what the chip's bus matrix answers is not documented either.
//
// The regions are programmed while the MPU is off, then it is enabled with PRIVDEFENA:
// privileged code (all of this firmware) keeps the default memory map everywhere but
// in the guards. HFNMIENA stays 0: the HardFault and NMI handlers run with the MPU off,
// so a fault handler entered from an overflowed stack can still stack its frame there.
// The region attribute: AP = 000 (no access at any privilege), XN, memory type bits as
// for normal SRAM (TEX 000, C 1, B 0, S 0), which only matter once the region allows
// an access.
#pragma once

#include <cstdint>
#include <span>

#include "hal/stm32g4/mmio.h"
#include "hal/stm32g4/regs/cortex_m4.h"

namespace mjc::stm32g4 {

// A no-access region: `bytes` (a power of two, 32 or more) at `base`, aligned to it.
struct GuardRegion {
  std::uint32_t base = 0;
  std::uint32_t bytes = 0;
};

constexpr bool ValidGuard(GuardRegion g) {
  return g.bytes >= 32 && (g.bytes & (g.bytes - 1)) == 0 && g.base % g.bytes == 0;
}

// RASR.SIZE for `bytes` = 2^(SIZE+1).
constexpr std::uint32_t MpuSizeField(std::uint32_t bytes) {
  std::uint32_t log2 = 0;
  while ((1u << log2) < bytes) ++log2;
  return log2 - 1;
}

// Programs the guards as regions 0.., disables the others and enables the MPU (with
// the barriers that make it take effect). False, with the MPU left off, when the core
// has fewer regions than guards or a guard is malformed.
inline bool EnableStackGuards(std::span<const GuardRegion> guards) {
  using namespace mpu;
  const std::uint32_t regions = type::kDregion.Get(Read32(kBase + kType));
  if (guards.size() > regions) return false;
  for (const GuardRegion& g : guards) {
    if (!ValidGuard(g)) return false;
  }
  DataSyncBarrier();  // every access before is done under the old map
  Write32(kBase + kCtrl, 0);
  for (std::uint32_t r = 0; r < regions; ++r) {
    Write32(kBase + kRnr, rnr::kRegion.Value(r));
    std::uint32_t base = 0, rasr = 0;
    if (r < guards.size()) {
      base = guards[r].base;
      rasr = rasr::kEnable.Bit() | rasr::kSize.Value(MpuSizeField(guards[r].bytes)) |
             rasr::kAp.Value(0b000) | rasr::kXn.Bit() | rasr::kC.Bit();
    }
    Write32(kBase + kRbar, base);  // VALID = 0: the region RNR selects
    Write32(kBase + kRasr, rasr);
  }
  Write32(kBase + kCtrl, ctrl::kEnable.Bit() | ctrl::kPrivdefena.Bit());
  DataSyncBarrier();
  InstructionSyncBarrier();
  return true;
}

}  // namespace mjc::stm32g4
