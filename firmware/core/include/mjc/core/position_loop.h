// Position loop on the motor-pulley angle: PID with conditional-integration
// anti-windup, derivative on the measurement (no kick on setpoint steps), velocity
// feed-forward, output saturated to the duty limit.
#pragma once

#include <cstdint>

#include "mjc/core/quantities.h"

namespace mjc {

using PerRadian = Unit<0, 0, 0, -1, 0>;
using PerRadianSecond = Unit<0, 0, -1, -1, 0>;
using SecondPerRadian = Unit<0, 0, 1, -1, 0>;

struct PositionLoopConfig {
  Fixed<PerRadian, 16> kp;                // duty per rad of error, 0..32767
  Fixed<PerRadianSecond, 16> ki;          // duty per rad·s, 0..32767
  Fixed<SecondPerRadian, 16> kd;          // duty per rad/s of motor velocity, 0..32767
  Fixed<SecondPerRadian, 16> kff;         // duty per rad/s of setpoint velocity
  Duty max_duty = Duty::FromDouble(0.9);  // |duty| limit, (0, 1)
  Duty integral_limit = Duty::FromDouble(0.3);  // |integral term| limit, [0, max_duty]
  // First-order low-pass on the motor velocity used by the D term:
  // ω_f += β·(ω − ω_f) each tick; β in (0, 1].
  Coefficient velocity_filter = Coefficient::FromDouble(0.05);
  std::uint32_t tick_hz = 10000;  // 100..100000
};

enum class PositionLoopError : std::uint8_t {
  kOk = 0,
  kNegativeGain = 1,
  kDutyLimitOutOfRange = 2,
  kIntegralLimitOutOfRange = 3,
  kFilterOutOfRange = 4,
  kTickRateOutOfRange = 5,
  kIntegralGainTooHigh = 6,  // ki >= 2·tick_hz
};

PositionLoopError Validate(const PositionLoopConfig& config);

// Wide sum of duty terms: ±128, so several saturated terms add without overflow.
using DutySum = Fixed<Unitless, 24>;

class PositionLoop {
 public:
  struct State {
    DutySum integral;
    Angle last_motor;
    AngularVelocity motor_velocity;  // filtered
    bool initialized = false;
    void Clear() { *this = State{}; }
  };

  // The terms of the last update, for telemetry and tuning.
  struct Status {
    DutySum p, i, d, ff;
    bool saturated = false;
  };

  // `config` must have passed Validate(); call Configure() after changing it.
  PositionLoop(const PositionLoopConfig* config, State* state);
  void Configure();

  // One tick: setpoint (rad) and its velocity (feed-forward), measured motor angle.
  Duty Update(Angle setpoint, AngularVelocity setpoint_velocity, Angle motor);

  const Status& status() const { return status_; }

 private:
  const PositionLoopConfig* config_;
  State* state_;
  Status status_;
  Fixed<PerRadian, 30> ki_per_tick_;  // ki / f_tick
  Fixed<Hertz, 0> tick_rate_;
};

}  // namespace mjc
