#include "mjc/host/robot_description.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <numbers>
#include <span>
#include <sstream>
#include <stdexcept>

#include "mjc/core/encoder.h"
#include "mjc/host/calibration_io.h"
#include "mjc/protocol/params.h"
#include "mjc/strict_json.h"

namespace mjc::host {
namespace {

using Json = nlohmann::json;

constexpr std::string_view kPulleyKeys[] = {"motor_radius_m", "joint_radius_m"};
constexpr std::string_view kSpringKeys[] = {"rate_N_per_m"};
constexpr std::string_view kMotorEncoderKeys[] = {"counts_per_rev", "gear_ratio",
                                                  "count_at_zero"};
constexpr std::string_view kJointEncoderKeys[] = {"counts_per_rev", "zero_count"};
constexpr std::string_view kLimitKeys[] = {"extension_deg", "flexion_deg", "torque_Nm"};
constexpr std::string_view kCableKeys[] = {"friction_Nm"};

// The board's joint limit (protocol::kJointAngleCeiling, ±1.6 rad), in degrees.
constexpr double kBoardJointLimitDeg =
    protocol::kJointAngleCeiling.ToDouble() * 180.0 / std::numbers::pi;
// The board's torque ceiling (protocol::kTorqueCeiling): a rating above it could not be
// held by the board.
constexpr double kBoardTorqueCeilingNm = protocol::kTorqueCeiling.ToDouble();

std::string Number(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.6g", v);
  return text;
}

using Reader = strict::FieldReader<Json>;

// A number within the plausible [lo, hi] (with `unit`, for the message).
double Plausible(const Reader& r, const Json& section, std::string_view prefix,
                 std::string_view key, double lo, double hi, std::string_view unit) {
  const double value = r.Double(section, prefix, key);
  if (!std::isfinite(value) || value < lo || value > hi) {
    r.Fail(strict::FieldName(prefix, key),
           "= " + Number(value) + " is outside the plausible [" + Number(lo) + ", " +
               Number(hi) + "]" + (unit.empty() ? "" : " ") + std::string(unit));
  }
  return value;
}

RobotDescription Parse(std::string_view text, std::string_view source) {
  const Json root = strict::ParseObject<Json>(text, source);
  if (const auto unknown = strict::UnknownKey(root, kRobotDescriptionKeys)) {
    throw std::runtime_error(std::string(source) + ": " + *unknown);
  }
  const Reader r(source);
  RobotDescription d;
  d.name = r.String(root, "", "name");
  const bool name_ok = !d.name.empty() && d.name.size() <= 64 &&
                       std::all_of(d.name.begin(), d.name.end(), [](char c) {
                         return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') ||
                                (c >= '0' && c <= '9') || c == '_' || c == '-' ||
                                c == '.';
                       });
  if (!name_ok) r.Fail("name", "= \"" + d.name + "\" is not 1-64 of [A-Za-z0-9_.-]");
  if (root.contains("description")) d.description = r.String(root, "", "description");

  // Pulleys of a finger joint: a few mm (a thumb PIP) to a few cm; outside that the
  // number is in the wrong unit (mm for m) rather than a joint.
  const Json& pulleys = r.Section(root, "pulleys", kPulleyKeys);
  d.motor_pulley_radius_m =
      Plausible(r, pulleys, "pulleys", "motor_radius_m", 0.002, 0.05, "m");
  d.joint_pulley_radius_m =
      Plausible(r, pulleys, "pulleys", "joint_radius_m", 0.002, 0.05, "m");
  const Json& springs = r.Section(root, "springs", kSpringKeys);
  d.spring_rate_N_per_m =
      Plausible(r, springs, "springs", "rate_N_per_m", 100.0, 100000.0, "N/m");

  const Json& motor = r.Section(root, "motor_encoder", kMotorEncoderKeys);
  d.motor_counts_per_rev = static_cast<std::int32_t>(
      r.Integer(motor, "motor_encoder", "counts_per_rev", 1, std::int64_t{1} << 20));
  d.gear_ratio = Plausible(r, motor, "motor_encoder", "gear_ratio", 1.0, 10000.0, "");
  d.motor_count_at_zero =
      static_cast<std::uint16_t>(r.Integer(motor, "motor_encoder", "count_at_zero", 0,
                                           std::numeric_limits<std::uint16_t>::max()));

  const Json& joint = r.Section(root, "joint_encoder", kJointEncoderKeys);
  d.joint_counts_per_rev = static_cast<std::int32_t>(
      r.Integer(joint, "joint_encoder", "counts_per_rev", 1, std::int64_t{1} << 20));
  if (d.joint_counts_per_rev != kJointCountsPerRev) {
    r.Fail("joint_encoder.counts_per_rev",
           "= " + std::to_string(d.joint_counts_per_rev) +
               ": the board reads a 14-bit absolute joint encoder (" +
               std::to_string(kJointCountsPerRev) + " counts a revolution)");
  }
  d.joint_zero_count = static_cast<std::uint16_t>(
      r.Integer(joint, "joint_encoder", "zero_count", 0, kJointCountsPerRev - 1));

  const Json& limits = r.Section(root, "limits", kLimitKeys);
  d.extension_limit_deg =
      Plausible(r, limits, "limits", "extension_deg", -kBoardJointLimitDeg, 0.0, "°");
  d.flexion_limit_deg =
      Plausible(r, limits, "limits", "flexion_deg", 0.0, kBoardJointLimitDeg, "°");
  if (!(d.extension_limit_deg < 0.0 && d.flexion_limit_deg > 0.0)) {
    r.Fail("limits",
           "must have extension_deg < 0 < flexion_deg (the joint at zero "
           "must be inside its travel)");
  }
  d.torque_limit_Nm =
      Plausible(r, limits, "limits", "torque_Nm", 1e-3, kBoardTorqueCeilingNm, "N·m");
  if (root.contains("cable")) {
    const Json& cable = r.Section(root, "cable", kCableKeys);
    d.cable_friction_Nm = Plausible(r, cable, "cable", "friction_Nm", 0.0,
                                    kMaxCableFriction.ToDouble(), "N·m");
  }

  // What follows from the parts must be a Maestro joint too (the ranges `mjc cal`
  // warns about, calibration_io.h): a ratio or stiffness outside them is a unit slip.
  const double alpha = d.Alpha();
  if (alpha < kPlausibleAlpha[0] || alpha > kPlausibleAlpha[1]) {
    r.Fail("pulleys", "give α = r_m / r_j = " + Number(alpha) +
                          ", outside the plausible [" + Number(kPlausibleAlpha[0]) +
                          ", " + Number(kPlausibleAlpha[1]) + "]");
  }
  const double stiffness = d.SeaStiffness();
  if (stiffness < kPlausibleStiffness[0] || stiffness > kPlausibleStiffness[1]) {
    r.Fail("springs.rate_N_per_m", "gives K = 2·k·r_j² = " + Number(stiffness) +
                                       " N·m/rad, outside the plausible [" +
                                       Number(kPlausibleStiffness[0]) + ", " +
                                       Number(kPlausibleStiffness[1]) + "] N·m/rad");
  }
  return d;
}

}  // namespace

std::optional<RobotDescription> ParseRobotDescription(std::string_view json_text,
                                                      std::string_view source,
                                                      std::string* why) {
  try {
    return Parse(json_text, source);
  } catch (const std::exception& e) {
    *why = e.what();
    return std::nullopt;
  }
}

std::optional<RobotDescription> LoadRobotDescription(const std::string& path,
                                                     std::string* why) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    *why = path + ": cannot open the robot description";
    return std::nullopt;
  }
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) {
    *why = path + ": read error";
    return std::nullopt;
  }
  return ParseRobotDescription(text.str(), path, why);
}

void UseRobotAlpha(const RobotDescription& robot, bool fit_alpha,
                   BacklashFitOptions* options) {
  options->fit_alpha = fit_alpha;
  options->alpha = robot.Alpha();
  options->alpha_min = robot.Alpha() * (1.0 - kAlphaFitSpan);
  options->alpha_max = robot.Alpha() * (1.0 + kAlphaFitSpan);
}

void UseRobotJoint(const RobotDescription& robot, protocol::CalibrationRecord* record) {
  record->sea_stiffness = Stiffness::Quantize(robot.SeaStiffness());
  record->joint_zero_count = robot.joint_zero_count;
  record->backlash.cable_friction = CableFrictionForRecord(robot.cable_friction_Nm);
}

double JointZeroShift(std::uint16_t held_zero, const RobotDescription& robot) {
  std::int32_t counts = std::int32_t{held_zero} - std::int32_t{robot.joint_zero_count};
  if (counts >= kJointCountsPerRev / 2) counts -= kJointCountsPerRev;
  if (counts < -kJointCountsPerRev / 2) counts += kJointCountsPerRev;
  return counts * (2.0 * std::numbers::pi / kJointCountsPerRev);
}

std::string DescribeRobot(const RobotDescription& robot, std::string_view source) {
  char text[320];
  std::snprintf(text, sizeof text,
                " (%.*s): α = %.4f (r_m %.2f mm / r_j %.2f mm), K = %.4f N·m/rad "
                "(2 × %.0f N/m × (%.2f mm)²), ",
                static_cast<int>(source.size()), source.data(), robot.Alpha(),
                robot.motor_pulley_radius_m * 1e3, robot.joint_pulley_radius_m * 1e3,
                robot.SeaStiffness(), robot.spring_rate_N_per_m,
                robot.joint_pulley_radius_m * 1e3);
  std::string out = robot.name + text;
  if (robot.cable_friction_Nm > 0) {
    std::snprintf(text, sizeof text, "cable friction %.3f N·m", robot.cable_friction_Nm);
    out += text;
  } else {
    out += "cable friction not modelled";
  }
  return out;
}

}  // namespace mjc::host
