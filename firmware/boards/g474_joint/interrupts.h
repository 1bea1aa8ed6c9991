// The board's interrupt entries and the IRQs they serve: the image's vector table puts
// each at 16 + its IRQ number (startup.cc), the virtual board registers each as its
// chip's handler for that number (sim_host/g474_board). One table, so both run the
// same entries on the same lines; `g474_joint_vectors` checks the linked table against
// ST's SVD.
#pragma once

#include <array>

#include "hal/stm32g4/regs/irq.h"
#include "hal/stm32g4/vector_table.h"

extern "C" {
// The 10 kHz control tick: TIM1's update (the PWM's repetition counter).
void TickInterrupt();
// FDCAN1 line 0: received frames into the CAN port's queue.
void CanLine0Interrupt();
// FDCAN1 line 1: bus-off, its recovery started and reported by TakeBusOff().
void CanLine1Interrupt();
}

namespace mjc::board {

using Handler = void (*)();

inline constexpr std::array<stm32g4::IrqHandler<Handler>, 3> kDriverIrqs{{
    {stm32g4::irq::kTim1Update, TickInterrupt},
    {stm32g4::irq::kFdcan1Line0, CanLine0Interrupt},
    {stm32g4::irq::kFdcan1Line1, CanLine1Interrupt},
}};

}  // namespace mjc::board
