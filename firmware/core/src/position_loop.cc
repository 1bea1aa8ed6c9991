#include "mjc/core/position_loop.h"

namespace mjc {

PositionLoopError Validate(const PositionLoopConfig& c) {
  if (c.kp.raw() < 0 || c.ki.raw() < 0 || c.kd.raw() < 0) {
    return PositionLoopError::kNegativeGain;
  }
  if (c.max_duty.raw() <= 0) return PositionLoopError::kDutyLimitOutOfRange;
  if (c.integral_limit.raw() < 0 || c.integral_limit > c.max_duty) {
    return PositionLoopError::kIntegralLimitOutOfRange;
  }
  if (c.velocity_filter.raw() <= 0 || c.velocity_filter > Coefficient(1)) {
    return PositionLoopError::kFilterOutOfRange;
  }
  if (c.tick_hz < 100 || c.tick_hz > 100000)
    return PositionLoopError::kTickRateOutOfRange;
  // ki / f_tick must fit the Q1.30 per-tick gain: ki < 2·f (ki is Q16, f an integer).
  if (static_cast<std::int64_t>(c.ki.raw()) >= (std::int64_t{2} * c.tick_hz) << 16) {
    return PositionLoopError::kIntegralGainTooHigh;
  }
  return PositionLoopError::kOk;
}

PositionLoop::PositionLoop(const PositionLoopConfig* config, State* state)
    : config_(config), state_(state) {
  Configure();
}

void PositionLoop::Configure() {
  tick_rate_ = Fixed<Hertz, 0>(config_->tick_hz);
  ki_per_tick_ = Divide<Fixed<PerRadian, 30>>(config_->ki, tick_rate_);
}

Duty PositionLoop::Update(Angle setpoint, AngularVelocity setpoint_velocity,
                          Angle motor) {
  if (!state_->initialized) {
    state_->last_motor = motor;
    state_->motor_velocity = AngularVelocity{};
    state_->integral = DutySum{};
    state_->initialized = true;
  }
  // Motor velocity: backward difference, low-passed.
  const auto raw_velocity = Mul<AngularVelocity>(motor - state_->last_motor, tick_rate_);
  state_->last_motor = motor;
  // 0 < β <= 1 (Validate), so the rounded product is no larger than its other factor.
  state_->motor_velocity += MulInRange<AngularVelocity>(
      config_->velocity_filter, raw_velocity - state_->motor_velocity);

  const Angle error = setpoint - motor;
  status_.p = Mul<DutySum>(config_->kp, error);
  status_.d = -Mul<DutySum>(config_->kd, state_->motor_velocity);
  status_.ff = Mul<DutySum>(config_->kff, setpoint_velocity);

  const DutySum limit = FixedCast<DutySum>(config_->max_duty);
  const DutySum without_i = status_.p + status_.d + status_.ff;
  const DutySum before = without_i + state_->integral;
  // Conditional integration: do not integrate further into a saturated output.
  const bool pushing_high = before >= limit && error.raw() > 0;
  const bool pushing_low = before <= -limit && error.raw() < 0;
  if (!pushing_high && !pushing_low) {
    const DutySum i_limit = FixedCast<DutySum>(config_->integral_limit);
    state_->integral =
        Clamp(state_->integral + Mul<DutySum>(ki_per_tick_, error), -i_limit, i_limit);
  }
  status_.i = state_->integral;

  const DutySum total = without_i + state_->integral;
  status_.saturated = total > limit || total < -limit;
  // |clamped| <= limit = max_duty·2^9 < 2^24 (a Duty is below 1), so FixedCast's
  // rounding fits 32 bits, floor(x/2^9 + 1/2) = (x + 2^8) >> 9, and its result is at
  // most max_duty's raw value: its saturation cannot act (on Cortex-M4 it cost 10
  // instructions a tick).
  const DutySum clamped = Clamp(total, -limit, limit);
  constexpr int kShift = DutySum::kFracBits - Duty::kFracBits;
  static_assert(kShift == 9);
  return Duty::FromRaw(
      static_cast<std::int16_t>((clamped.raw() + (1 << (kShift - 1))) >> kShift));
}

}  // namespace mjc
