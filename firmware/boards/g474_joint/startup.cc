// Reset and exception entry of the joint board (STM32G474): the chip-only part of its
// start-up (the vector table, the stack switch, the memory initialisation, the fault
// handler); the rest is shared with the virtual board (board.h).
//
// Reset_Handler: thread mode moves to the process stack (the main stack in SRAM) while
// exceptions keep the main stack pointer (the interrupt stack in CCM SRAM, loaded from
// vector 0), then StartUp(): the FPU first (CPACR, ARMv7-M B3.2.20: before any
// floating-point instruction, and nothing before it uses one), .data and .ccm_data
// copied, .bss and .ccm_bss zeroed, VTOR at this image's vector table (a bootloader
// below it may have left its own), static constructors, BringUp() (the crash record
// into the start-up report, the clock tree to 170 MHz), then main().
//
// The NMI goes to NmiHandler: an ECC double error of the flash (a calibration, identity
// or header page left half-written by a cut save or update) is recorded and cleared by
// the flash driver, and the read that hit it fails (the record store then takes the
// other page); any other NMI stops the board as a fault does.
//
// Every exception and interrupt without a driver goes to DefaultHandler: the bridge's
// enable line low and TIM1's main output off (its idle state: both low sides on, so the
// motor is braked, not left to run on its last duty), the exception number kept in a
// RAM word that survives the reset, and a system reset (AIRCR.SYSRESETREQ). The reset
// puts the pins back to analog mode (no output driver, no pull: GPIOx_MODER resets to
// all ones on most pins), where the board's pull-downs hold the bridge off; the
// next boot reports the crash (Startup().crashed). If even that fails (a fault while
// stacking onto an overflowed interrupt stack locks the core up), the watchdog resets
// the chip within 100 ms.
#include "hal/stm32g4/startup.h"

#include <cstdint>

#include "board.h"
#include "hal/stm32g4/flash.h"
#include "hal/stm32g4/mmio.h"
#include "hal/stm32g4/mpu.h"
#include "hal/stm32g4/nvic.h"
#include "hal/stm32g4/regs/cortex_m4.h"
#include "hal/stm32g4/regs/irq.h"
#include "hal/stm32g4/vector_table.h"
#include "interrupts.h"

extern "C" {
// Linker script symbols (linker/stm32g474.ld).
extern std::uint32_t __data_start[], __data_end[], __data_load[];
extern std::uint32_t __bss_start[], __bss_end[];
extern std::uint32_t __ccm_data_start[], __ccm_data_end[], __ccm_data_load[];
extern std::uint32_t __ccm_bss_start[], __ccm_bss_end[];
extern std::uint32_t __interrupt_stack_top[];
extern std::uint32_t __main_stack_top[];
// The no-access regions under the two stacks, and their size (a symbol's address).
extern std::uint32_t __main_stack_guard[], __interrupt_stack_guard[];
extern std::uint8_t __stack_guard_size[];
extern const std::uint32_t __vector_table[];
// The calibration pages' place in flash.
extern const std::uint8_t __calibration_start[];
// Shared with the bootloader across resets (the HANDOFF region).
extern mjc::boot::BootHandoff __boot_handoff;

void __libc_init_array();
int main();
[[noreturn]] void Reset_Handler();
[[noreturn]] void StartUp();
[[noreturn]] void DefaultHandler();
void NmiHandler();
}

namespace mjc::board {

std::uint32_t CalibrationAddress() {
  return static_cast<std::uint32_t>(
      reinterpret_cast<std::uintptr_t>(__calibration_start));
}

volatile boot::BootHandoff& Handoff() { return __boot_handoff; }

}  // namespace mjc::board

using mjc::stm32g4::Address;
using mjc::stm32g4::Read32;
using mjc::stm32g4::Write32;

// Naked: no prologue may touch the stack before the stack pointers are set.
__attribute__((naked)) void Reset_Handler() {
  asm volatile(
      "ldr r0, =__main_stack_top\n"
      "msr psp, r0\n"
      "movs r0, #2\n"  // CONTROL.SPSEL = 1: thread mode on PSP
      "msr control, r0\n"
      "isb\n"
      "b StartUp\n");
}

void StartUp() {
  namespace stm32g4 = mjc::stm32g4;
  stm32g4::EnableFpu();
  stm32g4::CopySection(__data_start, __data_end, __data_load);
  stm32g4::ZeroSection(__bss_start, __bss_end);
  stm32g4::CopySection(__ccm_data_start, __ccm_data_end, __ccm_data_load);
  stm32g4::ZeroSection(__ccm_bss_start, __ccm_bss_end);
  stm32g4::SetVectorTable(__vector_table);

  // Usage, bus and memory-management faults get their own vectors (here all the
  // default handler) instead of escalating; divisions by zero trap.
  namespace scb = stm32g4::scb;
  const Address shcsr = scb::kBase + scb::kShcsr;
  Write32(shcsr, Read32(shcsr) | scb::shcsr::kMemfaultena.Bit() |
                     scb::shcsr::kBusfaultena.Bit() | scb::shcsr::kUsgfaultena.Bit());
  const Address ccr = scb::kBase + scb::kCcr;
  Write32(ccr, Read32(ccr) | scb::ccr::kDiv0Trp.Bit());
  stm32g4::DataSyncBarrier();
  stm32g4::InstructionSyncBarrier();

  // Each stack's guard a no-access MPU region (hal/stm32g4/mpu.h): an overflow faults
  // there (MemManage, enabled above) at its first access. The linker script asserts
  // their size and alignment; if the MPU refused them anyway, the image runs without
  // (nothing better to do this early: no pin, no bus is up yet).
  const auto address = [](const void* p) {
    return static_cast<std::uint32_t>(reinterpret_cast<std::uintptr_t>(p));
  };
  const std::uint32_t guard_bytes = address(__stack_guard_size);
  const stm32g4::GuardRegion guards[] = {{address(__main_stack_guard), guard_bytes},
                                         {address(__interrupt_stack_guard), guard_bytes}};
  (void)stm32g4::EnableStackGuards(guards);

  __libc_init_array();
  mjc::board::BringUp();
  (void)main();
  DefaultHandler();  // main never returns; if it did, stop as for a fault
}

void NmiHandler() {
  if (!mjc::stm32g4::HandleFlashEccNmi()) DefaultHandler();
}

void DefaultHandler() {
  mjc::stm32g4::DisableInterrupts();
  mjc::board::StopBridge();
  std::uint32_t ipsr = 0;
  asm volatile("mrs %0, ipsr" : "=r"(ipsr));
  mjc::board::g_crash.exception = ipsr & 0x1FFu;
  mjc::board::g_crash.magic = mjc::board::kCrashMagic;
  mjc::stm32g4::RequestSystemReset();
  for (;;) {
  }
}

using mjc::board::Handler;

// Position 0 the interrupt stack's top; every other position from the IRQ table.
extern "C" __attribute__((section(".isr_vector"),
                          used)) constinit const mjc::stm32g4::VectorTable<Handler>
    kVectorTable = {
        __interrupt_stack_top,
        mjc::stm32g4::BuildVectorTable(
            mjc::stm32g4::ResetAndFaultHandlers(
                Handler{&Reset_Handler}, Handler{&NmiHandler}, Handler{&DefaultHandler}),
            Handler{&DefaultHandler}, Handler{nullptr}, mjc::board::kDriverIrqs)};
