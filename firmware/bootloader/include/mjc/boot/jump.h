// The hand-over to an image on a Cortex-M4 (ARMv7-M), the last thing the bootloader
// does; target only. The caller has disabled every interrupt in the NVIC, cleared the
// pending ones and returned the peripherals it used to their reset state (on the G474:
// g474_platform.h, ReleasePeripherals), with PRIMASK set all along. Then, as the core
// does at reset (ARMv7-M B1.5.5, "Reset behavior"):
//   VTOR ← the image's vector table (B3.2.5; 512-aligned, checked by the header),
//   MSP ← its word 0, CONTROL ← 0 (privileged, main stack, no floating-point context),
//   PRIMASK cleared, and a branch to its word 1, the reset handler (a Thumb address,
//   checked by the image check).
// Nothing uses the stack after MSP changes: the last steps are one asm block.
#pragma once

#if defined(__arm__)

#include <cstdint>

namespace mjc::boot {

[[noreturn]] inline void JumpToImage(std::uint32_t vector_table) {
  constexpr std::uint32_t kVtor = 0xE000ED08u;  // SCB->VTOR (B3.2.2)
  *reinterpret_cast<volatile std::uint32_t*>(kVtor) = vector_table;
  const std::uint32_t stack_pointer =
      *reinterpret_cast<const volatile std::uint32_t*>(vector_table);
  const std::uint32_t reset_handler =
      *reinterpret_cast<const volatile std::uint32_t*>(vector_table + 4);
  asm volatile(
      "dsb\n"
      "isb\n"  // the new VTOR in effect before anything else happens
      "msr msp, %0\n"
      "movs r3, #0\n"
      "msr control, r3\n"  // SPSEL = 0, nPRIV = 0, FPCA = 0
      "isb\n"
      "cpsie i\n"  // every interrupt is disabled in the NVIC: none can come
      "bx %1\n"
      :
      : "r"(stack_pointer), "r"(reset_handler)
      : "r3", "memory");
  __builtin_unreachable();
}

}  // namespace mjc::boot

#endif
