#include "mjc/core/supervisor.h"

namespace mjc {

SupervisorConfigError Validate(const SupervisorConfig& c) {
  using E = SupervisorConfigError;
  if (c.joint_min >= c.joint_max) return E::kJointRange;
  if (c.motor_min >= c.motor_max) return E::kMotorRange;
  if (c.torque_max <= Torque{}) return E::kTorqueMax;
  if (c.velocity_max <= AngularVelocity{}) return E::kVelocityMax;
  if (c.joint_jump_max <= Angle{}) return E::kJointJumpMax;
  if (c.stuck_motor_travel <= Angle{}) return E::kStuckTravel;
  if (c.stuck_duty <= Duty{}) return E::kStuckDuty;
  if (c.motor_stuck_ticks == 0) return E::kMotorStuckTicks;
  if (c.stuck_hold_error <= Angle{}) return E::kStuckHoldError;
  return E::kOk;
}

bool Supervisor::Clear(const SupervisorInput& in) {
  if (Evaluate<false>(in) != Fault::kNone) return false;
  state_->Clear();
  Remember(in);
  return true;
}

}  // namespace mjc
