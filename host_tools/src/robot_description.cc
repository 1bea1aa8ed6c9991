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

// The board's joint limit (SupervisorConfig::joint_min/max, ±1.6 rad), in degrees.
constexpr double kBoardJointLimitDeg = 1.6 * 180.0 / std::numbers::pi;

std::string Number(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.6g", v);
  return text;
}

// Reads one file, throwing std::runtime_error with the message the caller returns.
class Reader {
 public:
  explicit Reader(std::string_view source) : source_(source) {}

  [[noreturn]] void Fail(std::string_view field, const std::string& what) const {
    throw std::runtime_error(std::string(source_) + ": field '" + std::string(field) +
                             "' " + what);
  }

  const Json& Section(const Json& root, std::string_view key,
                      std::span<const std::string_view> known) const {
    const Json& section = Get(root, "", key);
    if (!section.is_object()) Fail(key, "must be an object");
    if (const auto unknown = strict::UnknownKey(section, known, std::string(key) + ".")) {
      throw std::runtime_error(std::string(source_) + ": " + *unknown);
    }
    return section;
  }

  // A number within [lo, hi] (with `unit` and why that range, for the message).
  double Double(const Json& section, std::string_view prefix, std::string_view key,
                double lo, double hi, std::string_view unit) const {
    const Json& v = Get(section, prefix, key);
    const std::string name = Name(prefix, key);
    if (!v.is_number()) Fail(name, "must be a number");
    const double value = v.get<double>();
    if (!std::isfinite(value) || value < lo || value > hi) {
      Fail(name, "= " + Number(value) + " is outside the plausible [" + Number(lo) +
                     ", " + Number(hi) + "]" + (unit.empty() ? "" : " ") +
                     std::string(unit));
    }
    return value;
  }

  std::int64_t Integer(const Json& section, std::string_view prefix, std::string_view key,
                       std::int64_t lo, std::int64_t hi) const {
    const Json& v = Get(section, prefix, key);
    const std::string name = Name(prefix, key);
    if (!v.is_number_integer()) Fail(name, "must be an integer");
    const bool too_big =
        v.is_number_unsigned() && v.get<std::uint64_t>() > static_cast<std::uint64_t>(hi);
    const std::int64_t value = too_big ? hi + 1 : v.get<std::int64_t>();
    if (too_big || value < lo || value > hi) {
      Fail(name, "= " + v.dump() + " is outside [" + std::to_string(lo) + ", " +
                     std::to_string(hi) + "]");
    }
    return value;
  }

  std::string String(const Json& root, std::string_view key) const {
    const Json& v = Get(root, "", key);
    if (!v.is_string()) Fail(key, "must be a string");
    return v.get<std::string>();
  }

 private:
  static std::string Name(std::string_view prefix, std::string_view key) {
    return strict::FieldName(prefix, key);
  }

  const Json& Get(const Json& object, std::string_view prefix,
                  std::string_view key) const {
    const Json* v = strict::Member(object, key);
    if (v == nullptr) Fail(Name(prefix, key), "is missing");
    return *v;
  }

  std::string_view source_;
};

RobotDescription Parse(std::string_view text, std::string_view source) {
  Json root;
  try {
    root = Json::parse(text);
  } catch (const Json::exception& e) {
    throw std::runtime_error(std::string(source) + ": not valid JSON: " + e.what());
  }
  if (!root.is_object()) {
    throw std::runtime_error(std::string(source) + ": the top level must be an object");
  }
  if (const auto unknown = strict::UnknownKey(root, kRobotDescriptionKeys)) {
    throw std::runtime_error(std::string(source) + ": " + *unknown);
  }
  const Reader r(source);
  RobotDescription d;
  d.name = r.String(root, "name");
  const bool name_ok = !d.name.empty() && d.name.size() <= 64 &&
                       std::all_of(d.name.begin(), d.name.end(), [](char c) {
                         return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') ||
                                (c >= '0' && c <= '9') || c == '_' || c == '-' ||
                                c == '.';
                       });
  if (!name_ok) r.Fail("name", "= \"" + d.name + "\" is not 1-64 of [A-Za-z0-9_.-]");
  if (root.contains("description")) d.description = r.String(root, "description");

  // Pulleys of a finger joint: a few mm (a thumb PIP) to a few cm; outside that the
  // number is in the wrong unit (mm for m) rather than a joint.
  const Json& pulleys = r.Section(root, "pulleys", kPulleyKeys);
  d.motor_pulley_radius_m =
      r.Double(pulleys, "pulleys", "motor_radius_m", 0.002, 0.05, "m");
  d.joint_pulley_radius_m =
      r.Double(pulleys, "pulleys", "joint_radius_m", 0.002, 0.05, "m");
  const Json& springs = r.Section(root, "springs", kSpringKeys);
  d.spring_rate_N_per_m =
      r.Double(springs, "springs", "rate_N_per_m", 100.0, 100000.0, "N/m");

  const Json& motor = r.Section(root, "motor_encoder", kMotorEncoderKeys);
  d.motor_counts_per_rev = static_cast<std::int32_t>(
      r.Integer(motor, "motor_encoder", "counts_per_rev", 1, std::int64_t{1} << 20));
  d.gear_ratio = r.Double(motor, "motor_encoder", "gear_ratio", 1.0, 10000.0, "");
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
      r.Double(limits, "limits", "extension_deg", -kBoardJointLimitDeg, 0.0, "°");
  d.flexion_limit_deg =
      r.Double(limits, "limits", "flexion_deg", 0.0, kBoardJointLimitDeg, "°");
  if (!(d.extension_limit_deg < 0.0 && d.flexion_limit_deg > 0.0)) {
    r.Fail("limits",
           "must have extension_deg < 0 < flexion_deg (the joint at zero "
           "must be inside its travel)");
  }
  d.torque_limit_Nm = r.Double(limits, "limits", "torque_Nm", 1e-3, 5.0, "N·m");

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
}

double JointZeroShift(std::uint16_t held_zero, const RobotDescription& robot) {
  std::int32_t counts = std::int32_t{held_zero} - std::int32_t{robot.joint_zero_count};
  if (counts >= kJointCountsPerRev / 2) counts -= kJointCountsPerRev;
  if (counts < -kJointCountsPerRev / 2) counts += kJointCountsPerRev;
  return counts * (2.0 * std::numbers::pi / kJointCountsPerRev);
}

std::string DescribeRobot(const RobotDescription& robot, std::string_view source) {
  char text[256];
  std::snprintf(text, sizeof text,
                " (%.*s): α = %.4f (r_m %.2f mm / r_j %.2f mm), K = %.4f N·m/rad "
                "(2 × %.0f N/m × (%.2f mm)²)",
                static_cast<int>(source.size()), source.data(), robot.Alpha(),
                robot.motor_pulley_radius_m * 1e3, robot.joint_pulley_radius_m * 1e3,
                robot.SeaStiffness(), robot.spring_rate_N_per_m,
                robot.joint_pulley_radius_m * 1e3);
  return robot.name + text;
}

}  // namespace mjc::host
