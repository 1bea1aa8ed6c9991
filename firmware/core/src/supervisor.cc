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

template <bool kWithHistory>
Fault Supervisor::Evaluate(const SupervisorInput& in) const {
  const SupervisorConfig& c = *config_;
  if (in.joint_status == JointFrameStatus::kParityError) return Fault::kJointParity;
  if (in.joint_status == JointFrameStatus::kErrorFlag) return Fault::kJointErrorFlag;
  if (kWithHistory && state_->have_history) {
    if (Abs(in.joint - state_->last_joint) > c.joint_jump_max) return Fault::kJointJump;
    if (in.joint_count == state_->last_joint_count &&
        Abs(in.motor - state_->motor_at_joint_change) > c.stuck_motor_travel) {
      return Fault::kJointStuck;
    }
    if (state_->motor_frozen_ticks >= c.motor_stuck_ticks) return Fault::kMotorStuck;
  }
  if (in.joint < c.joint_min || in.joint > c.joint_max) return Fault::kJointAngleLimit;
  if (in.motor < c.motor_min || in.motor > c.motor_max) return Fault::kMotorAngleLimit;
  if (Abs(in.torque) > c.torque_max) return Fault::kTorqueLimit;
  if (Abs(in.joint_velocity) > c.velocity_max) return Fault::kVelocityLimit;
  if (in.tick_overrun) return Fault::kTickOverrun;
  if (in.external != Fault::kNone) return in.external;
  return Fault::kNone;
}

void Supervisor::Remember(const SupervisorInput& in) {
  if (!state_->have_history || in.joint_count != state_->last_joint_count) {
    state_->motor_at_joint_change = in.motor;
  }
  state_->last_joint = in.joint;
  state_->last_joint_count = in.joint_count;
  state_->last_motor_count = in.motor_count;
  state_->have_history = true;
}

Fault Supervisor::Check(std::uint32_t tick, const SupervisorInput& in) {
  if (state_->latched != Fault::kNone) return state_->latched;
  // The frozen-motor counter includes this tick before it is judged. A motor held at
  // its setpoint is not driven to move, whatever duty the hold takes. The count is
  // tested first: while the motor turns it differs, and duty and error go unread.
  const bool frozen = state_->have_history && in.motor_count == state_->last_motor_count;
  if (frozen && Abs(in.applied_duty) >= config_->stuck_duty &&
      Abs(in.motor_error) > config_->stuck_hold_error) {
    ++state_->motor_frozen_ticks;
  } else {
    state_->motor_frozen_ticks = 0;
  }
  const Fault f = Evaluate<true>(in);
  if (f != Fault::kNone) {
    state_->latched = f;
    state_->fault_tick = tick;
    return f;
  }
  Remember(in);
  return Fault::kNone;
}

bool Supervisor::Clear(const SupervisorInput& in) {
  if (Evaluate<false>(in) != Fault::kNone) return false;
  state_->Clear();
  Remember(in);
  return true;
}

}  // namespace mjc
