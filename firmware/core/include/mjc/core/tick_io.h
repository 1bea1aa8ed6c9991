// What the control tick exchanges with the hardware: the sensor words it reads at its
// start and the drive it writes at its end. The hardware seam (hal::JointIo) needs only
// this, not the whole tick.
#pragma once

#include <cstdint>

#include "mjc/core/quantities.h"

namespace mjc {

// What the hardware (or the simulator) read at the start of the tick.
struct Sample {
  std::uint16_t motor_count = 0;  // quadrature timer count
  std::uint16_t joint_frame = 0;  // the joint encoder's 16-bit SPI read frame
  bool tick_overrun = false;      // the previous tick did not finish in time
};

struct Actuation {
  Duty duty;                    // zero whenever the bridge is disabled
  bool bridge_enabled = false;  // the H-bridge enable line
};

}  // namespace mjc
