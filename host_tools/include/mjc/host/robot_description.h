// A robot description: one small JSON file per Maestro joint (index MCP, thumb PIP,
// ...) saying what is built into that joint and nowhere else: its pulleys, its springs,
// its encoders and their zeros, its travel and torque limits. `mjc calibrate --robot`
// takes the transmission ratio α and the SEA stiffness K from it, so a board is never
// left with another joint's numbers; `mjc sim --robot-description` builds the simulated
// plant from it. The shipped descriptions are in robots/ at the repository root
// (robots/README.md gives the format).
//
//   α = r_m / r_j          motor-pulley over joint-pulley radius (the cable's ratio)
//   K = 2 · k · r_j²       N·m/rad: two antagonistic springs of rate k (N/m) each,
//                          acting on the joint pulley of radius r_j
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "mjc/host/calibration_fit.h"
#include "mjc/protocol/calibration_record.h"

namespace mjc::host {

struct RobotDescription {
  std::string name;         // [A-Za-z0-9_.-]+, shown by the tools
  std::string description;  // free text, optional

  // "pulleys": the cable runs from the motor pulley to the joint pulley.
  double motor_pulley_radius_m = 0.01;  // r_m, plausible [0.002, 0.05] m
  double joint_pulley_radius_m = 0.01;  // r_j, plausible [0.002, 0.05] m
  // "springs": each of the two SEA springs, plausible [100, 100000] N/m.
  double spring_rate_N_per_m = 3150.0;  // k
  // "motor_encoder": quadrature edges per motor-shaft revolution [1, 2^20], gearhead
  // reduction (motor turns per pulley turn) [1, 10000], timer count at θ_m = 0.
  std::int32_t motor_counts_per_rev = 2048;
  double gear_ratio = 100.0;
  std::uint16_t motor_count_at_zero = 0;
  // "joint_encoder": counts per joint revolution (the board reads a 14-bit absolute
  // encoder: 16384, nothing else) and the count at θ_j = 0 [0, 16383].
  std::int32_t joint_counts_per_rev = 16384;
  std::uint16_t joint_zero_count = 0;
  // "limits": the joint's travel (extension negative, flexion positive), degrees, each
  // within the board's ±91.6° (1.6 rad) joint limit and extension < 0 < flexion; the
  // SEA torque the joint may carry, (0, 5] N·m.
  double extension_limit_deg = -45.0;
  double flexion_limit_deg = 90.0;
  double torque_limit_Nm = 1.0;
  // "cable" (optional): the sheath's friction at the joint, N·m, [0, 5]: the SEA
  // torque beyond which the spring pulls the cable through its slack (robots/README.md
  // says how to measure it). 0 (absent): not modelled, the board's play operator holds
  // the cable in its slack.
  double cable_friction_Nm = 0.0;

  // α = r_m / r_j.
  double Alpha() const { return motor_pulley_radius_m / joint_pulley_radius_m; }
  // K = 2·k·r_j², N·m/rad (the plant's SeaParams::Stiffness, the record's sea_stiffness).
  double SeaStiffness() const {
    return 2.0 * spring_rate_N_per_m * joint_pulley_radius_m * joint_pulley_radius_m;
  }
};

// The keys of a description: top level, then each section's.
inline constexpr std::string_view kRobotDescriptionKeys[] = {
    "name",          "description",   "pulleys", "springs",
    "motor_encoder", "joint_encoder", "limits",  "cable"};

// Reads a description from JSON text; `source` names it in messages. nullopt with the
// reason in *why (naming the file and the field, with the plausible range) for
// malformed JSON, a missing field, a wrong type, an unknown key (named with the known
// key it resembles: mjc/strict_json.h), or a value outside the plausible range above,
// including the derived α outside [0.5, 2] and K outside [0.063, 6.3] N·m/rad (the
// ranges `mjc cal` warns about). Never throws.
std::optional<RobotDescription> ParseRobotDescription(std::string_view json_text,
                                                      std::string_view source,
                                                      std::string* why);

// The same from a file (a missing or unreadable file is refused the same way).
std::optional<RobotDescription> LoadRobotDescription(const std::string& path,
                                                     std::string* why);

// How far around the description's α a fit of α searches (--fit-alpha): ±20 %, enough
// for pulleys worn or wound other than drawn, small enough that a sweep cannot trade
// α for slack. A fit that ends on either bound is refused (FitBacklash).
inline constexpr double kAlphaFitSpan = 0.2;

// The calibration fit for this joint: α fixed at robot.Alpha(), or, with fit_alpha,
// searched within robot.Alpha()·[1 − kAlphaFitSpan, 1 + kAlphaFitSpan]. Only the α
// fields of *options change.
void UseRobotAlpha(const RobotDescription& robot, bool fit_alpha,
                   BacklashFitOptions* options);

// The joint's own numbers in a calibration record: the SEA stiffness K (quantised to
// the record's Q7.24), the cable friction τ_f (to the record's mN·m) and the joint
// encoder's zero count. The fit's c_r, c_l and α are not touched.
void UseRobotJoint(const RobotDescription& robot, protocol::CalibrationRecord* record);

// What to add to joint angles the board measured with its `held_zero` count so they
// read as with the description's zero, rad: (held_zero − robot.joint_zero_count) counts
// of 2π/16384, the difference wrapped into [−8192, 8192). The sweep is recorded with
// the zero the board holds; the record sent after it carries the description's.
double JointZeroShift(std::uint16_t held_zero, const RobotDescription& robot);

// One line for people: "maestro-default (robots/maestro-default.json): α = 1.000
// (r_m 10.0 mm / r_j 10.0 mm), K = 0.630 N·m/rad (2 × 3150 N/m × (10.0 mm)²)".
std::string DescribeRobot(const RobotDescription& robot, std::string_view source);

}  // namespace mjc::host
