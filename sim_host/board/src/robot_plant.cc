#include "mjc/sim/robot_plant.h"

#include <stdexcept>
#include <string>

namespace mjc::sim {

plant::PlantParams PlantForRobot(const host::RobotDescription& robot,
                                 const plant::PlantParams& base,
                                 const ControlConfig& board, std::string_view source) {
  const MotorEncoderConfig& encoder = board.motor_encoder;
  const double board_ratio =
      static_cast<double>(encoder.gear_numerator) / encoder.gear_denominator;
  if (robot.motor_counts_per_rev != encoder.counts_per_rev ||
      robot.gear_ratio != board_ratio) {
    throw std::runtime_error(
        std::string(source) + ": motor_encoder (" +
        std::to_string(robot.motor_counts_per_rev) + " counts, " +
        std::to_string(robot.gear_ratio) + ":1) is not the board's (" +
        std::to_string(encoder.counts_per_rev) + " counts, " +
        std::to_string(board_ratio) + ":1, compiled into its MotorEncoderConfig)");
  }
  plant::PlantParams p = base;
  p.name = base.name + "+" + robot.name;
  p.cable.alpha = robot.Alpha();
  p.sea.spring_rate_N_per_m = robot.spring_rate_N_per_m;
  p.sea.joint_pulley_radius_m = robot.joint_pulley_radius_m;
  p.motor.gear_ratio = robot.gear_ratio;
  p.sensors.motor_counts_per_rev = robot.motor_counts_per_rev;
  p.sensors.motor_count_at_zero = robot.motor_count_at_zero;
  p.sensors.joint_zero_count = robot.joint_zero_count;
  if (robot.cable_friction_Nm > 0) p.cable.coulomb_Nm = robot.cable_friction_Nm;
  plant::ValidatePlantParams(p, std::string(source) + " on " + base.name);
  return p;
}

}  // namespace mjc::sim
