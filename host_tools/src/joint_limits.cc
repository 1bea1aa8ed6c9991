#include "mjc/host/joint_limits.h"

#include <cmath>
#include <cstdio>

#include "mjc/host/units.h"

namespace mjc::host {
namespace {

using protocol::ParamId;

// The list's entry of an id it has.
const protocol::ParamInfo& InfoOf(ParamId id) {
  for (const protocol::ParamInfo& p : protocol::kParams) {
    if (p.id == id) return p;
  }
  return protocol::kParams[0];  // not reached: the ids named here are the list's
}

// `value` in `id`'s format, rounded towards zero: a limit never comes out looser than
// the description's (the travel's ends lie either side of zero, the torque above it).
ParamSetting Inward(ParamId id, double value) {
  const protocol::ParamInfo& info = InfoOf(id);
  ParamSetting s;
  s.info = &info;
  s.given = value;
  s.raw = static_cast<std::int32_t>(std::trunc(std::ldexp(value, info.frac_bits)));
  s.exact = ParamValueOf(info, s.raw) == value;
  return s;
}

}  // namespace

std::vector<ParamSetting> JointLimitSettings(const RobotDescription& robot) {
  return {Inward(ParamId::kJointTorqueLimit, robot.torque_limit_Nm),
          Inward(ParamId::kJointAngleMin, DegToRad(robot.extension_limit_deg)),
          Inward(ParamId::kJointAngleMax, DegToRad(robot.flexion_limit_deg))};
}

ParamWriteOutcome SendJointLimits(BoardClient& board, const RobotDescription& robot,
                                  int timeout_ms) {
  const std::vector<ParamSetting> settings = JointLimitSettings(robot);
  return WriteParams(board, settings, timeout_ms);
}

std::optional<JointTravel> ReadJointTravel(BoardClient& board, int timeout_ms,
                                           std::string* why) {
  const protocol::ParamInfo& min = InfoOf(ParamId::kJointAngleMin);
  const protocol::ParamInfo& max = InfoOf(ParamId::kJointAngleMax);
  const protocol::ParamInfo& alpha = InfoOf(ParamId::kCalibrationAlpha);
  const std::vector<const protocol::ParamInfo*> which = {&min, &max, &alpha};
  const auto readings = ReadParams(board, which, timeout_ms, why);
  if (!readings || readings->size() != 3) return std::nullopt;
  JointTravel t;
  t.min_rad = ParamValueOf(min, (*readings)[0].raw);
  t.max_rad = ParamValueOf(max, (*readings)[1].raw);
  t.alpha = ParamValueOf(alpha, (*readings)[2].raw);
  return t;
}

std::string TravelViolation(double amplitude_deg, const JointTravel& travel) {
  const double joint_deg = std::abs(travel.alpha) * amplitude_deg;
  const double min_deg = RadToDeg(travel.min_rad);
  const double max_deg = RadToDeg(travel.max_rad);
  // The travel reached the board rounded inwards by up to a step of its format (2^-24
  // rad, 3.4e-6°): an excursion within a few steps of it is on the travel, not beyond.
  constexpr double kSlackDeg = 1e-5;
  if (joint_deg <= max_deg + kSlackDeg && -joint_deg >= min_deg - kSlackDeg) return "";
  char text[200];
  std::snprintf(text, sizeof text,
                "%.1f° moves the joint ±%.1f° (α %.3f), beyond its travel [%.1f°, %.1f°]",
                amplitude_deg, joint_deg, travel.alpha, min_deg, max_deg);
  return text;
}

}  // namespace mjc::host
