// Memory-mapped register access and the few CPU instructions the drivers need: the one
// place where the STM32G474 build and the host build differ.
//
// On the Cortex-M4 an access is a plain volatile load or store of its width, inlined:
// a driver's register read is one LDR, exactly what hand-written CMSIS code compiles to.
// On the host every access goes to the RegisterSpace that a driver test or the virtual
// board bound: models of the chip's peripherals, written from the reference manual, so
// the same driver sources run against them on x86.
//
// Widths matter on this chip (RM0440): SPI's data register packs one or two frames by
// access width, so the drivers say which they mean (Read16/Write16 vs Read32/Write32).
#pragma once

#include <cstdint>

#if !defined(__arm__)
#include <cstdio>
#include <cstdlib>
#endif

namespace mjc::stm32g4 {

// A bus address on the chip (peripheral registers, message RAM, flash).
using Address = std::uint32_t;

#if defined(__arm__)

inline std::uint32_t Read32(Address a) {
  return *reinterpret_cast<const volatile std::uint32_t*>(a);
}
inline std::uint16_t Read16(Address a) {
  return *reinterpret_cast<const volatile std::uint16_t*>(a);
}
inline void Write32(Address a, std::uint32_t v) {
  *reinterpret_cast<volatile std::uint32_t*>(a) = v;
}
inline void Write16(Address a, std::uint16_t v) {
  *reinterpret_cast<volatile std::uint16_t*>(a) = v;
}

// WFI: sleep until an interrupt is pending (its handler runs before WFI returns when
// interrupts are enabled).
inline void WaitForInterrupt() { asm volatile("wfi" ::: "memory"); }
// PRIMASK: mask and unmask every configurable interrupt.
inline void DisableInterrupts() { asm volatile("cpsid i" ::: "memory"); }
inline void EnableInterrupts() { asm volatile("cpsie i" ::: "memory"); }
// Barriers the reference manual asks for between some accesses (e.g. the two words of
// a flash double-word program, after changing the vector table).
inline void DataSyncBarrier() { asm volatile("dsb" ::: "memory"); }
inline void InstructionSyncBarrier() { asm volatile("isb" ::: "memory"); }

#else  // the host: accesses reach models

// What the host binds: the chip's address space. `bytes` is 2 or 4; addresses are
// aligned to it (the drivers never make unaligned accesses).
class RegisterSpace {
 public:
  virtual ~RegisterSpace() = default;
  virtual std::uint32_t Read(Address address, unsigned bytes) = 0;
  virtual void Write(Address address, std::uint32_t value, unsigned bytes) = 0;
  // WFI: the virtual board advances its time to the next interrupt and runs the
  // pending handlers, as the core would, before returning.
  virtual void WaitForInterrupt() {}
  // PRIMASK set (true) or cleared.
  virtual void MaskInterrupts(bool /*masked*/) {}
};

namespace detail {
inline RegisterSpace* g_space = nullptr;

[[noreturn]] inline void Unbound(Address a) {
  std::fprintf(stderr, "stm32g4: register access at 0x%08X with no RegisterSpace bound\n",
               static_cast<unsigned>(a));
  std::abort();
}
inline RegisterSpace& Space(Address a) {
  if (g_space == nullptr) Unbound(a);
  return *g_space;
}
}  // namespace detail

// Every access goes to `space` until the next call; nullptr unbinds (an access then
// aborts, naming its address). One space per process at a time.
inline void BindRegisterSpace(RegisterSpace* space) { detail::g_space = space; }

inline std::uint32_t Read32(Address a) { return detail::Space(a).Read(a, 4); }
inline std::uint16_t Read16(Address a) {
  return static_cast<std::uint16_t>(detail::Space(a).Read(a, 2));
}
inline void Write32(Address a, std::uint32_t v) { detail::Space(a).Write(a, v, 4); }
inline void Write16(Address a, std::uint16_t v) { detail::Space(a).Write(a, v, 2); }

inline void WaitForInterrupt() {
  if (detail::g_space != nullptr) detail::g_space->WaitForInterrupt();
}
inline void DisableInterrupts() {
  if (detail::g_space != nullptr) detail::g_space->MaskInterrupts(true);
}
inline void EnableInterrupts() {
  if (detail::g_space != nullptr) detail::g_space->MaskInterrupts(false);
}
inline void DataSyncBarrier() {}
inline void InstructionSyncBarrier() {}

#endif

}  // namespace mjc::stm32g4
