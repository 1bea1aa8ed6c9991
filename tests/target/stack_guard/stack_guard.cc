// The stack guard on a real Cortex-M4 MPU (QEMU's mps2-an386 models the ARMv7-M MPU
// with 8 regions): the joint image's EnableStackGuards (hal/stm32g4/mpu.h) puts a
// no-access region at the bottom of a thread stack, and a recursion that runs that
// stack down must take a MemManage fault with the faulting address in the guard
// (MMFSR.DACCVIOL with MMFAR valid, or MSTKERR when the fault comes while stacking).
// As on the joint board, thread mode runs on the process stack (PSP) and the fault
// handler on the main stack (MSP), which is not the overflowed one.
//
// Exit status: 0 when the MemManage fault came from the guard with the rest of the map
// unchanged (the handler reads RAM, the image's .data and writes over semihosting);
// 2 when the recursion went past the guard without a fault (the stack would have
// overwritten what lies below it); 3 when the MPU could not be programmed; 4 when the
// MemManage fault was not the guard's; 128 + n for any other exception n.
#include <array>
#include <cstdint>
#include <cstdio>

#include "hal/stm32g4/mpu.h"
#include "semihost.h"

namespace {

using mjc::stm32g4::GuardRegion;

// The thread stack: a guard of 256 bytes at its bottom (a frame up to that size cannot
// step over it), aligned to the guard's size as the MPU requires.
constexpr std::uint32_t kGuardBytes = 256;
constexpr std::uint32_t kStackBytes = 4096;
alignas(kGuardBytes) std::uint8_t g_thread_stack[kStackBytes];
volatile std::uint32_t g_depth = 0;
volatile bool g_deeper = true;  // always: a recursion the compiler cannot prove endless
volatile std::uint32_t g_checked_data = 0x5AFE5AFEu;  // .data: read by the handler

std::uint32_t GuardBase() {
  return static_cast<std::uint32_t>(reinterpret_cast<std::uintptr_t>(g_thread_stack));
}

// Each level keeps 64 bytes of its own on the stack; the stack holds about 50 of them.
// Past 2 × that, the stack has overrun its guard: no fault came.
[[gnu::noinline]] void Recurse(std::uint32_t n) {
  volatile std::uint8_t frame[64];
  frame[0] = static_cast<std::uint8_t>(n);
  g_depth = n;
  if (n > 2 * kStackBytes / 64) {
    mjc::qemu::SemihostWrite("FAIL: the stack ran past its guard without a fault\n");
    mjc::qemu::SemihostExit(2);
  }
  if (g_deeper) Recurse(n + 1);
  frame[63] = frame[0];  // the frame lives across the call: no tail call
}

// Thread mode onto the process stack at `top`, then Recurse(0); never returns.
[[gnu::naked]] void RunOnProcessStack(std::uint32_t /*top*/) {
  asm volatile(
      "msr psp, r0\n"
      "movs r1, #2\n"  // CONTROL.SPSEL = 1
      "msr control, r1\n"
      "isb\n"
      "movs r0, #0\n"
      "bl %c0\n"
      "b .\n" ::"i"(&Recurse));
}

volatile std::uint32_t& Scs(std::uint32_t address) {
  return *reinterpret_cast<volatile std::uint32_t*>(address);
}

extern "C" void MemManageHandler() {
  // ARMv7-M B3.2.15/B3.2.17: CFSR's MMFSR byte, MMFAR.
  const std::uint32_t cfsr = Scs(0xE000ED28u);
  const std::uint32_t mmfar = Scs(0xE000ED34u);
  const bool daccviol = (cfsr & (1u << 1)) != 0, mstkerr = (cfsr & (1u << 4)) != 0;
  const bool mmarvalid = (cfsr & (1u << 7)) != 0;
  const bool in_guard =
      mmarvalid && mmfar >= GuardBase() && mmfar < GuardBase() + kGuardBytes;
  char line[160];
  std::snprintf(line, sizeof line,
                "MemManage: CFSR 0x%08lx MMFAR 0x%08lx guard 0x%08lx depth %lu\n",
                static_cast<unsigned long>(cfsr), static_cast<unsigned long>(mmfar),
                static_cast<unsigned long>(GuardBase()),
                static_cast<unsigned long>(g_depth));
  mjc::qemu::SemihostWrite(line);
  if (g_checked_data != 0x5AFE5AFEu || !((daccviol && in_guard) || mstkerr)) {
    mjc::qemu::SemihostWrite("FAIL: not the guard's fault\n");
    mjc::qemu::SemihostExit(4);
  }
  mjc::qemu::SemihostWrite("PASS: the stack overflow faulted in its guard\n");
  mjc::qemu::SemihostExit(0);
}

extern "C" void OtherFault() {
  std::uint32_t ipsr = 0;
  asm volatile("mrs %0, ipsr" : "=r"(ipsr));
  mjc::qemu::SemihostWrite("FAIL: an exception other than MemManage\n");
  mjc::qemu::SemihostExit(static_cast<int>(128u + (ipsr & 0xFFu)));
}

// The image's own table stays at 0; this one (system exceptions only) takes over.
using Handler = void (*)();
alignas(128) Handler g_vectors[16];

}  // namespace

int main() {
  for (Handler& h : g_vectors) h = OtherFault;
  g_vectors[4] = MemManageHandler;  // exception 4
  Scs(0xE000ED08u) =
      static_cast<std::uint32_t>(reinterpret_cast<std::uintptr_t>(g_vectors));
  Scs(0xE000ED24u) |= 1u << 16;  // SHCSR.MEMFAULTENA: MemManage its own exception
  asm volatile("dsb\n\tisb" ::: "memory");

  const std::array<GuardRegion, 1> guards{{{GuardBase(), kGuardBytes}}};
  if (!mjc::stm32g4::EnableStackGuards(guards)) {
    mjc::qemu::SemihostWrite("FAIL: the MPU could not be programmed\n");
    return 3;
  }
  // The rest of the map is unchanged (PRIVDEFENA): RAM, .data and semihosting work.
  char line[96];
  std::snprintf(line, sizeof line, "MPU on: guard 0x%08lx + %lu, .data 0x%08lx\n",
                static_cast<unsigned long>(GuardBase()),
                static_cast<unsigned long>(kGuardBytes),
                static_cast<unsigned long>(g_checked_data));
  mjc::qemu::SemihostWrite(line);
  RunOnProcessStack(GuardBase() + kStackBytes);
}
