// The Maestro joint's control configuration: the signal chain's defaults and the
// position-loop gains tuned for its drive. What a joint board runs until a host writes
// other gains; the simulated board runs the same.
#pragma once

#include "mjc/core/control_tick.h"

namespace mjc::app {

constexpr ControlConfig DefaultJointConfig() {
  ControlConfig c;
  // Position-loop gains for the Maestro joint's drive (sim_host/params: 13.7 Ω,
  // 11.4 mN·m/A, 100:1, 12 V). kff ≈ k_e·N/V_supply cancels the back-EMF at the
  // commanded velocity; kp and ki hold the tracking error of a 25° 0.5 Hz sine under the
  // interface load to well under a degree; kd damps the cable pick-up at the dead-band
  // edges.
  c.position.kp = Fixed<PerRadian, 16>::FromDouble(40.0);
  c.position.ki = Fixed<PerRadianSecond, 16>::FromDouble(200.0);
  c.position.kd = Fixed<SecondPerRadian, 16>::FromDouble(0.05);
  c.position.kff = Fixed<SecondPerRadian, 16>::FromDouble(0.095);
  c.position.max_duty = Duty::FromDouble(0.9);
  c.position.integral_limit = Duty::FromDouble(0.5);
  return c;
}

}  // namespace mjc::app
