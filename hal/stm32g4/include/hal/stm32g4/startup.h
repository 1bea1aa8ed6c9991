// What every STM32G474 image does between reset and its static constructors: the FPU's
// access, the memory sections a linker script describes (initial data copied from
// flash, zero-initialised data cleared), VTOR at the image's own vector table; and the
// vector table's layout. Each image's Reset_Handler calls these in its own order (the
// joint image also switches stacks, initialises CCM SRAM and enables the fault vectors).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "hal/stm32g4/mmio.h"
#include "hal/stm32g4/regs/cortex_m4.h"
#include "hal/stm32g4/vector_table.h"

namespace mjc::stm32g4 {

// Full access to the FPU (CPACR.CP10/CP11 = 0b11, ARMv7-M B3.2.20), with the barriers
// that make it take effect: before any floating-point instruction.
inline void EnableFpu() {
  const Address cpacr = scb::kBase + scb::kCpacr;
  Write32(cpacr,
          Read32(cpacr) | scb::cpacr::kCp10.Value(0b11) | scb::cpacr::kCp11.Value(0b11));
  DataSyncBarrier();
  InstructionSyncBarrier();
}

// The bytes between two linker-script symbols.
inline std::size_t SectionBytes(const std::uint32_t* begin, const std::uint32_t* end) {
  return static_cast<std::size_t>(reinterpret_cast<std::uintptr_t>(end) -
                                  reinterpret_cast<std::uintptr_t>(begin));
}

// An initialised-data section [begin, end) filled from its load address in flash.
inline void CopySection(std::uint32_t* begin, std::uint32_t* end,
                        const std::uint32_t* load) {
  std::memcpy(begin, load, SectionBytes(begin, end));
}

// A zero-initialised section [begin, end) cleared.
inline void ZeroSection(std::uint32_t* begin, std::uint32_t* end) {
  std::memset(begin, 0, SectionBytes(begin, end));
}

// VTOR at `table` (a bootloader below the image may have left its own there). The
// caller adds the barriers once its system control writes are done.
inline void SetVectorTable(const std::uint32_t* table) {
  Write32(scb::kBase + scb::kVtor,
          static_cast<std::uint32_t>(reinterpret_cast<std::uintptr_t>(table)));
}

// The table as the linker places it in .isr_vector: the initial main stack pointer,
// then positions 1..kVectorCount-1 (BuildVectorTable).
template <class Handler>
struct VectorTable {
  const void* initial_stack_pointer;
  std::array<Handler, kVectorCount - 1> handlers;
};

// Reset at `reset`, the NMI at `nmi`, every other system exception at `fault` (the
// images' handler that stops the board and resets it). The NMI has a handler of its
// own: the flash raises it for an ECC double error (hal/stm32g4/flash.h), which a power
// cut during an erase or program leaves behind — resetting on it would read the same
// double word at the next start, and the next, forever.
template <class Handler>
constexpr SystemHandlers<Handler> ResetAndFaultHandlers(Handler reset, Handler nmi,
                                                        Handler fault) {
  return {.reset = reset,
          .nmi = nmi,
          .hard_fault = fault,
          .mem_manage = fault,
          .bus_fault = fault,
          .usage_fault = fault,
          .svcall = fault,
          .debug_monitor = fault,
          .pendsv = fault,
          .systick = fault};
}

}  // namespace mjc::stm32g4
