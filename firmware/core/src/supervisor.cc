#include "mjc/core/supervisor.h"

#include <algorithm>
#include <limits>

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

void Supervisor::SetVelocitySpan(std::uint16_t span_ticks, std::uint32_t tick_hz) {
  constexpr int kShift = Angle::kFracBits - AngularVelocity::kFracBits;
  static_assert(kShift >= 0);
  if (span_ticks == 0 || tick_hz == 0) {  // no mean to take: any motion trips
    travel_max_ = Angle{};
    return;
  }
  // |v| < 2^31 LSBs, so v·2^4·span < 2^51 with span < 2^16: exact in 64 bits before
  // the division. A threshold beyond Angle's range is one no travel can pass.
  const std::int64_t v = config_->velocity_max.raw();
  const std::int64_t travel = (v << kShift) * static_cast<std::int64_t>(span_ticks) /
                              static_cast<std::int64_t>(tick_hz);
  travel_max_ = Angle::FromRaw(static_cast<std::int32_t>(
      std::min<std::int64_t>(travel, std::numeric_limits<std::int32_t>::max())));
}

bool Supervisor::Clear(const SupervisorInput& in) {
  if (Evaluate<false>(in) != Fault::kNone) return false;
  state_->Clear();
  Remember(in);
  return true;
}

}  // namespace mjc
