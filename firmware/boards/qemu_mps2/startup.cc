// Reset and exception entry for QEMU mps2-an386 test images: copy .data, clear .bss,
// turn on the FPU, run static constructors, call main(), and hand main's return value
// to QEMU as its exit status. Any fault ends the run with a distinct status instead of
// hanging the test.
#include <cstdint>
#include <cstring>

#include "semihost.h"

extern "C" {
extern std::uint32_t __data_start[], __data_end[], __data_load[];
extern std::uint32_t __bss_start[], __bss_end[];
extern std::uint32_t __stack_top[];

void __libc_init_array();
// -nostartfiles drops crti/crtn; newlib's __libc_init_array still calls these.
void _init() {}
void _fini() {}
// ... and crtbegin, which defines the handle that libstdc++'s static destructors
// register against (one image, no shared objects: any unique address will do).
void* __dso_handle = &__dso_handle;

int main();
[[noreturn]] void Reset_Handler();
[[noreturn]] void Fault_Handler();
}

namespace {

// Exit status for a fault: 128 + exception number, like a shell reports a signal.
[[noreturn]] void ReportFault() {
  std::uint32_t ipsr = 0;
  asm volatile("mrs %0, ipsr" : "=r"(ipsr));
  mjc::qemu::SemihostWrite("FAULT: exception taken, image stopped\n");
  mjc::qemu::SemihostExit(static_cast<int>(128u + (ipsr & 0xFFu)));
}

}  // namespace

void Fault_Handler() { ReportFault(); }

void Reset_Handler() {
  const auto data_bytes =
      static_cast<std::size_t>(reinterpret_cast<std::uintptr_t>(__data_end) -
                               reinterpret_cast<std::uintptr_t>(__data_start));
  std::memcpy(__data_start, __data_load, data_bytes);
  const auto bss_bytes =
      static_cast<std::size_t>(reinterpret_cast<std::uintptr_t>(__bss_end) -
                               reinterpret_cast<std::uintptr_t>(__bss_start));
  std::memset(__bss_start, 0, bss_bytes);

  // CPACR: full access to CP10 and CP11 (the FPU) before any FP instruction runs.
  volatile std::uint32_t* const cpacr =
      reinterpret_cast<volatile std::uint32_t*>(0xE000ED88u);
  *cpacr = *cpacr | (0xFu << 20);
  asm volatile("dsb\n\tisb" ::: "memory");

  __libc_init_array();
  mjc::qemu::SemihostExit(main());
}

using Handler = void (*)();

// The initial stack pointer, then the Cortex-M4 system exceptions; test images enable
// no peripheral interrupt. A constant initialiser, so it is laid out at link time.
struct VectorTable {
  const void* initial_stack_pointer;
  Handler handlers[15];
};

extern const VectorTable kVectorTable;
__attribute__((section(".isr_vector"), used)) const VectorTable kVectorTable = {
    __stack_top,
    {
        Reset_Handler,
        Fault_Handler,  // NMI
        Fault_Handler,  // HardFault
        Fault_Handler,  // MemManage
        Fault_Handler,  // BusFault
        Fault_Handler,  // UsageFault
        nullptr, nullptr, nullptr, nullptr,
        Fault_Handler,  // SVCall
        Fault_Handler,  // DebugMonitor
        nullptr,
        Fault_Handler,  // PendSV
        Fault_Handler,  // SysTick
    },
};
