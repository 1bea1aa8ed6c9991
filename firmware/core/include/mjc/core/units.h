// Physical units as compile-time exponent vectors.
//
// A quantity's unit is a type: Unit<mass, length, time, angle, current>, each an
// integer exponent of kg, m, s, rad, A. The radian is kept as a dimension of its own
// (SI treats it as 1) so that torque (N·m per rad of twist, i.e. J/rad) and energy (J)
// are different types: τ·θ is energy, τ·θ̇ is power, and adding a torque to an energy
// does not compile. Products and quotients of quantities carry the product and quotient
// of their units; nothing here exists at run time.
#pragma once

#include <type_traits>

namespace mjc {

template <int kMass, int kLength, int kTime, int kAngle, int kCurrent>
struct Unit {
  static constexpr int mass = kMass;
  static constexpr int length = kLength;
  static constexpr int time = kTime;
  static constexpr int angle = kAngle;
  static constexpr int current = kCurrent;
};

template <class A, class B>
using UnitProduct = Unit<A::mass + B::mass, A::length + B::length, A::time + B::time,
                         A::angle + B::angle, A::current + B::current>;

template <class A, class B>
using UnitQuotient = Unit<A::mass - B::mass, A::length - B::length, A::time - B::time,
                          A::angle - B::angle, A::current - B::current>;

// Named units used by the joint board. Torque is N·m per radian of cable twist
// (M L² T⁻² A⁻¹) so that stiffness 2·k·r_j² (N·m/rad) times an angle is a torque.
using Unitless = Unit<0, 0, 0, 0, 0>;
using Radian = Unit<0, 0, 0, 1, 0>;
using Second = Unit<0, 0, 1, 0, 0>;
using Hertz = Unit<0, 0, -1, 0, 0>;
using RadianPerSecond = Unit<0, 0, -1, 1, 0>;
using RadianPerSecond2 = Unit<0, 0, -2, 1, 0>;
using NewtonMeter = Unit<1, 2, -2, -1, 0>;
using NewtonMeterPerRadian = Unit<1, 2, -2, -2, 0>;
using NewtonMeterSecondPerRadian = Unit<1, 2, -1, -2, 0>;
using Watt = Unit<1, 2, -3, 0, 0>;
using Joule = Unit<1, 2, -2, 0, 0>;
using Ampere = Unit<0, 0, 0, 0, 1>;
using Volt = Unit<1, 2, -3, 0, -1>;

static_assert(std::is_same_v<UnitProduct<NewtonMeter, RadianPerSecond>, Watt>);
static_assert(std::is_same_v<UnitProduct<NewtonMeter, Radian>, Joule>);
static_assert(std::is_same_v<UnitProduct<Watt, Second>, Joule>);
static_assert(std::is_same_v<UnitProduct<NewtonMeterPerRadian, Radian>, NewtonMeter>);
static_assert(std::is_same_v<UnitProduct<Volt, Ampere>, Watt>);

}  // namespace mjc
