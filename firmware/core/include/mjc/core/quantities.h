// The joint board's quantities and their Q formats. FIXED_POINT.md (next to this
// header's library) tables every format with its range, resolution and the reason it
// was chosen; change one here only together with that table.
#pragma once

#include <cstdint>
#include <numbers>

#include "mjc/core/fixed.h"

namespace mjc {

// Q7.24: ±128 rad, 6.0e-8 rad. θ_m, θ_j, θ̃_j, c_r, c_l, setpoints.
using Angle = Fixed<Radian, 24>;
// Q4.27: ±16 rad, 7.5e-9 rad. The attachment model's joint angle (attachment_model.h),
// whose per-tick steps are a velocity.
using ModelAngle = Fixed<Radian, 27>;
// Q11.20: ±2048 rad/s, 9.5e-7 rad/s. Joint and motor-pulley velocity.
using AngularVelocity = Fixed<RadianPerSecond, 20>;
// Q7.24: ±128 N·m, 6.0e-8 N·m. SEA torque, limits.
using Torque = Fixed<NewtonMeter, 24>;
// Q7.24: ±128 N·m/rad, 6.0e-8 N·m/rad. SEA stiffness 2·k·r_j².
using Stiffness = Fixed<NewtonMeterPerRadian, 24>;
// Q7.24: ±128 N·m·s/rad, 6.0e-8 N·m·s/rad. Identified attachment damping b_i.
using Damping = Fixed<NewtonMeterSecondPerRadian, 24>;
// Q7.24: ±128 W, 6.0e-8 W. Interface power τ·θ̇_j.
using Power = Fixed<Watt, 24>;
// Q31.32 in int64: ±2.1e9 J, 2.3e-10 J. Energy totals read out of the accumulator.
using Energy = Fixed<Joule, 32, std::int64_t>;
// Q0.31: [-1, 1) s, 4.7e-10 s. Tick period and other sub-second durations.
using Duration = Fixed<Second, 31>;
// Q15.16: ±32768 Hz, 1.5e-5 Hz. Trajectory frequencies, rates.
using Frequency = Fixed<Hertz, 16>;
// Q15.16: ±32768, 1.5e-5. Dimensionless gains and ratios (α, PID gains per unit).
using Ratio = Fixed<Unitless, 16>;
// Q3.28: ±8, 3.7e-9. Pulley ratio α = r_m / r_j and other precise dimensionless
// scales: α multiplies angles of up to ~1 rad, so 3.7e-9 relative keeps α·θ_m within
// one Angle LSB.
using Scale = Fixed<Unitless, 28>;
// Q0.15 in int16: [-1, 1), 3.1e-5. H-bridge duty; the G474's 20 kHz PWM has 8500
// counts (13 bits) per period, so 15 bits lose nothing.
using Duty = Fixed<Unitless, 15, std::int16_t>;
// Q1.30: ±2, 9.3e-10. The Eigen scalar of estimator and observer matrices, whose
// gains are below 1 and whose states are normalised.
using Coefficient = Fixed<Unitless, 30>;

namespace literals {

// Compile-time literals. Degrees convert to radians at compile time.
consteval Angle operator""_rad(long double v) {
  return Angle::FromDouble(static_cast<double>(v));
}
consteval Angle operator""_deg(long double v) {
  return Angle::FromDouble(static_cast<double>(v) * (std::numbers::pi / 180.0));
}
consteval AngularVelocity operator""_rad_s(long double v) {
  return AngularVelocity::FromDouble(static_cast<double>(v));
}
consteval Torque operator""_Nm(long double v) {
  return Torque::FromDouble(static_cast<double>(v));
}
consteval Stiffness operator""_Nm_rad(long double v) {
  return Stiffness::FromDouble(static_cast<double>(v));
}
consteval Power operator""_W(long double v) {
  return Power::FromDouble(static_cast<double>(v));
}
consteval Duration operator""_s(long double v) {
  return Duration::FromDouble(static_cast<double>(v));
}
consteval Frequency operator""_Hz(long double v) {
  return Frequency::FromDouble(static_cast<double>(v));
}

}  // namespace literals

}  // namespace mjc
