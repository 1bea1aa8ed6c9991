// The simulated plant of a described joint (mjc/host/robot_description.h): a parameter
// set supplies what a description does not say (motor, cable slack and friction, joint
// inertia, interface, sensor noise), the description what is built into that joint.
#pragma once

#include <string_view>

#include "mjc/core/control_tick.h"
#include "mjc/host/robot_description.h"
#include "mjc/plant/params.h"

namespace mjc::sim {

// `base` with the description's transmission and sensors:
//   cable.alpha                  = r_m / r_j
//   sea.spring_rate_N_per_m      = k,  sea.joint_pulley_radius_m = r_j
//   sensors.motor_counts_per_rev, motor_count_at_zero, joint_zero_count, and
//   motor.gear_ratio             = the description's
//   cable.coulomb_Nm             = its cable friction, when it gives one (> 0)
// then checked as any parameter set (plant::ValidatePlantParams). The board reads its
// motor encoder through `board`'s compiled-in MotorEncoderConfig (counts and gear
// ratio): a description whose encoder differs from it would be a joint that board
// cannot drive, and is refused. Throws std::runtime_error naming `source` and the
// field.
plant::PlantParams PlantForRobot(const host::RobotDescription& robot,
                                 const plant::PlantParams& base,
                                 const ControlConfig& board, std::string_view source);

}  // namespace mjc::sim
