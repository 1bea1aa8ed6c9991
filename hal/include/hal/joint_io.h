// The control tick's hardware seam. Called at 10 kHz, so it is a compile-time
// interface (a concept satisfied by a concrete class per platform), never a vtable:
// the STM32G4 driver reads the timer and the SPI frame, the simulator reads its plant.
#pragma once

#include <concepts>

#include "mjc/core/tick_io.h"

namespace mjc::hal {

// What the tick needs from the hardware:
//   ISR_Read():  the sensor words of this tick (quadrature timer count, joint SPI frame,
//                overrun flag) — sampled as close to the tick's start as possible;
//   ISR_Write(): the H-bridge duty and enable line, applied until the next tick.
template <class T>
concept JointIo = requires(T io, const Actuation& actuation) {
  { io.ISR_Read() } -> std::same_as<Sample>;
  { io.ISR_Write(actuation) } -> std::same_as<void>;
};

}  // namespace mjc::hal
