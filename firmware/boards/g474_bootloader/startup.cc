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
// DefaultHandler at every IRQ position. The NMI first asks the flash driver whether it
// was an ECC double error (a header or image page left half-written by a cut update):
// then the error is recorded and the read that hit it fails, and the bootloader treats
// the image as unreadable and stays on the bus, instead of resetting into the same read.
#include "hal/stm32g4/startup.h"

#include <array>
#include <cstdint>

#include "hal/stm32g4/flash.h"
#include "hal/stm32g4/gpio.h"
#include "hal/stm32g4/nvic.h"
#include "hal/stm32g4/vector_table.h"

extern "C" {
// Linker script symbols (linker/stm32g474_bootloader.ld).
extern std::uint32_t __data_start[], __data_end[], __data_load[];
extern std::uint32_t __bss_start[], __bss_end[];
extern std::uint32_t __main_stack_top[];
extern const std::uint32_t __vector_table[];

void __libc_init_array();
int main();
[[noreturn]] void Reset_Handler();
[[noreturn]] void DefaultHandler();
void NmiHandler();
}

void Reset_Handler() {
  mjc::stm32g4::DisableInterrupts();
  mjc::stm32g4::EnableFpu();
  mjc::stm32g4::CopySection(__data_start, __data_end, __data_load);
  mjc::stm32g4::ZeroSection(__bss_start, __bss_end);
  mjc::stm32g4::SetVectorTable(__vector_table);
  mjc::stm32g4::DataSyncBarrier();
  mjc::stm32g4::InstructionSyncBarrier();
  __libc_init_array();
  (void)main();
  DefaultHandler();  // main never returns
}

void NmiHandler() {
  if (!mjc::stm32g4::HandleFlashEccNmi()) DefaultHandler();
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

namespace {

using Handler = void (*)();
constexpr std::array<mjc::stm32g4::IrqHandler<Handler>, 0> kNoIrqs{};

}  // namespace

extern "C" __attribute__((section(".isr_vector"),
                          used)) constinit const mjc::stm32g4::VectorTable<Handler>
    kVectorTable = {
        __main_stack_top,
        mjc::stm32g4::BuildVectorTable(
            mjc::stm32g4::ResetAndFaultHandlers(
                Handler{&Reset_Handler}, Handler{&NmiHandler}, Handler{&DefaultHandler}),
            Handler{&DefaultHandler}, Handler{nullptr}, kNoIrqs)};
