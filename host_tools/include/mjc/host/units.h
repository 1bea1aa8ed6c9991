// Angle units on the host: the firmware and the wire work in radians; files and
// messages meant for people use degrees.
#pragma once

#include <numbers>

namespace mjc::host {

inline constexpr double kRadPerDeg = std::numbers::pi / 180.0;

constexpr double DegToRad(double deg) { return deg * kRadPerDeg; }
constexpr double RadToDeg(double rad) { return rad / kRadPerDeg; }

}  // namespace mjc::host
