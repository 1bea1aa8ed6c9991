// What a debugger's halt does to the board (RM0440 "Debug support", DBGMCU freeze bits;
// TIM1 "Debug mode"). By default a halted core stops nothing: the IWDG counts on and
// resets the chip within its period (100 ms here) of a breakpoint, and TIM1 keeps
// switching the H-bridge at the duty the last tick left, with no tick to stop it.
// With DBG_IWDG_STOP the watchdog's counter stops while the core is halted; with
// DBG_TIM1_STOP TIM1's counter stops and its outputs are disabled as if MOE were
// cleared, so they take their idle levels (OSSI = 1: high sides off, low sides on, the
// motor braked — bridge_pwm.h). Running again, both go on from where they were.
//
// Set at every start-up, not only in debug builds or when DHCSR.C_DEBUGEN is set: the
// bits act only while the core is halted, and only a debugger can halt it (a core
// locked up by a double fault is not halted: the watchdog still resets it). There is
// one build of the image, and the one flashed on a lab board is the one a probe will
// be attached to, often to a board already running (C_DEBUGEN read at start-up would
// miss that attach). The bits belong to the debug domain: a system reset keeps them,
// a power-on reset clears them, so the bootloader after a first run is covered too.
//
// TIM3 (the motor encoder) is left running on purpose: frozen, it would miss the edges
// of a motor turned by hand during the halt and the count would be wrong ever after.
#pragma once

#include "hal/stm32g4/mmio.h"
#include "hal/stm32g4/regs/dbgmcu.h"

namespace mjc::stm32g4 {

inline void FreezeOnDebugHalt() {
  using namespace dbgmcu;
  Write32(kBase + kApb1lFz, Read32(kBase + kApb1lFz) | apb1l_fz::kDbgIwdgStop.Bit());
  Write32(kBase + kApb2Fz, Read32(kBase + kApb2Fz) | apb2_fz::kDbgTim1Stop.Bit());
}

}  // namespace mjc::stm32g4
