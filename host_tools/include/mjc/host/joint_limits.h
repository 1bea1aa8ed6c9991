// The joint's own limits on the board. A robot description's torque and travel limits
// (robots/README.md, "limits") become the board's joint-limit parameters
// (joint_torque_limit, joint_angle_min, joint_angle_max: protocol/params.h, access
// kJointLimit): the board takes a tighter one and refuses a looser one until its next
// reset, and its torque_max never exceeds joint_torque_limit. `mjc calibrate --robot`
// and `mjc trial --robot` send them before anything moves.
//
// And the check `mjc trial` makes before anything moves: a trial turns the motor pulley
// ±A about neutral (0), the joint follows at α·A (α = r_m/r_j, the calibration's), so
// an amplitude whose α·A leaves the joint's travel the board holds is refused.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "mjc/host/board_client.h"
#include "mjc/host/param_io.h"
#include "mjc/host/robot_description.h"

namespace mjc::host {

// The description's limits as writes of the three joint-limit parameters, each
// rounded inwards to its format (never looser than the description).
std::vector<ParamSetting> JointLimitSettings(const RobotDescription& robot);

// Sends them (WriteParams: each answered and read back). A board holding a tighter
// limit (an earlier description's, since its reset) refuses with kBeyondJointLimit,
// which *why names with the limit it holds.
ParamWriteOutcome SendJointLimits(BoardClient& board, const RobotDescription& robot,
                                  int timeout_ms);

// The joint's travel the board holds (joint_angle_min, joint_angle_max, rad) and the
// calibration's α.
struct JointTravel {
  double min_rad = 0;
  double max_rad = 0;
  double alpha = 1;
};
std::optional<JointTravel> ReadJointTravel(BoardClient& board, int timeout_ms,
                                           std::string* why);

// Empty when a motion of ±amplitude_deg of the motor pulley about neutral keeps the
// joint within `travel`; otherwise why not, naming the amplitude, the joint's angle and
// the travel ("25.0° moves the joint ±31.3° (α 1.250), beyond its travel
// [-45.0°, 30.0°]").
std::string TravelViolation(double amplitude_deg, const JointTravel& travel);

}  // namespace mjc::host
