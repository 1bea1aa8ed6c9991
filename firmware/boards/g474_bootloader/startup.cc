// Reset and exception entry of the CAN bootloader (STM32G474).
//
// Reset_Handler runs on the main stack the core loaded from vector 0 and masks every
// interrupt first (PRIMASK): the bootloader polls its CAN controller and takes no
// interrupt until it hands over. Then the FPU's access (CPACR, ARMv7-M B3.2.20: before
// any floating-point instruction; the application enables it too), .data copied, .bss
// zeroed, VTOR at this vector table, static constructors, main(). The handoff block
// (.handoff) is neither copied nor zeroed.
//
// Every exception goes to DefaultHandler: the bridge's enable low (it already is), and a
// system reset. The bootloader never enables a peripheral interrupt, so the table holds
// DefaultHandler at every IRQ position.
#include <array>
#include <cstdint>
#include <cstring>

#include "hal/stm32g4/gpio.h"
#include "hal/stm32g4/mmio.h"
#include "hal/stm32g4/nvic.h"
#include "hal/stm32g4/regs/cortex_m4.h"
#include "hal/stm32g4/vector_table.h"

extern "C" {
// Linker script symbols (linker/stm32g474_bootloader.ld).
extern std::uint32_t __data_start[], __data_end[], __data_load[];
extern std::uint32_t __bss_start[], __bss_end[];
extern std::uint32_t __main_stack_top[];
extern const std::uint32_t __vector_table[];

void __libc_init_array();
void _init() {}
void _fini() {}
void* __dso_handle = &__dso_handle;
// Objects live for the whole run: no destructor is registered (newlib's __cxa_atexit
// would allocate).
int __aeabi_atexit(void* /*object*/, void (* /*destructor*/)(void*), void* /*dso*/) {
  return 0;
}

int main();
[[noreturn]] void Reset_Handler();
[[noreturn]] void DefaultHandler();
}

using mjc::stm32g4::Read32;
using mjc::stm32g4::Write32;

// No heap: the vtables of hal::Flash and hal::CanPort name deleting destructors.
void operator delete(void* /*pointer*/) noexcept { DefaultHandler(); }
void operator delete(void* /*pointer*/, std::size_t /*bytes*/) noexcept {
  DefaultHandler();
}

void Reset_Handler() {
  mjc::stm32g4::DisableInterrupts();
  namespace scb = mjc::stm32g4::scb;
  const mjc::stm32g4::Address cpacr = scb::kBase + scb::kCpacr;
  Write32(cpacr,
          Read32(cpacr) | scb::cpacr::kCp10.Value(0b11) | scb::cpacr::kCp11.Value(0b11));
  mjc::stm32g4::DataSyncBarrier();
  mjc::stm32g4::InstructionSyncBarrier();
  const auto bytes = [](const std::uint32_t* begin, const std::uint32_t* end) {
    return static_cast<std::size_t>(reinterpret_cast<std::uintptr_t>(end) -
                                    reinterpret_cast<std::uintptr_t>(begin));
  };
  std::memcpy(__data_start, __data_load, bytes(__data_start, __data_end));
  std::memset(__bss_start, 0, bytes(__bss_start, __bss_end));
  Write32(scb::kBase + scb::kVtor,
          static_cast<std::uint32_t>(reinterpret_cast<std::uintptr_t>(__vector_table)));
  mjc::stm32g4::DataSyncBarrier();
  mjc::stm32g4::InstructionSyncBarrier();
  __libc_init_array();
  (void)main();
  DefaultHandler();  // main never returns
}

void DefaultHandler() {
  mjc::stm32g4::DisableInterrupts();
  // The bridge's enable low (a no-op unless GPIOB's clock is on, and then it already
  // is low: nothing in the bootloader sets it).
  mjc::stm32g4::WritePin({mjc::stm32g4::Port::kB, 10}, false);
  mjc::stm32g4::RequestSystemReset();
  for (;;) {
  }
}

using Handler = void (*)();

struct VectorTable {
  const void* initial_stack_pointer;
  std::array<Handler, mjc::stm32g4::kVectorCount - 1> handlers;
};

namespace {

constexpr mjc::stm32g4::SystemHandlers<Handler> kSystem{
    .reset = Reset_Handler,
    .nmi = DefaultHandler,
    .hard_fault = DefaultHandler,
    .mem_manage = DefaultHandler,
    .bus_fault = DefaultHandler,
    .usage_fault = DefaultHandler,
    .svcall = DefaultHandler,
    .debug_monitor = DefaultHandler,
    .pendsv = DefaultHandler,
    .systick = DefaultHandler,
};
constexpr std::array<mjc::stm32g4::IrqHandler<Handler>, 0> kNoIrqs{};

}  // namespace

extern "C" __attribute__((section(".isr_vector"),
                          used)) constinit const VectorTable kVectorTable = {
    __main_stack_top, mjc::stm32g4::BuildVectorTable(kSystem, Handler{&DefaultHandler},
                                                     Handler{nullptr}, kNoIrqs)};
