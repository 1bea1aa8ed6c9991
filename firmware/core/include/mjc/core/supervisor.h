// The supervisor: every check that can stop the motor, run on every tick's sample
// before any duty is applied. A fault disables the bridge in the tick that detects it
// and latches: the bridge stays off until the host clears the fault and the cause is
// gone (Clear() re-runs the checks on the current sample).
#pragma once

#include <cstdint>

#include "mjc/core/encoder.h"
#include "mjc/core/quantities.h"

namespace mjc {

// Stable numbers grouped by range: they travel over CAN and into logs; never renumber.
enum class Fault : std::uint16_t {
  kNone = 0,
  // 100–199: sensors
  kJointParity = 100,     // joint encoder frame failed parity
  kJointErrorFlag = 101,  // joint encoder raised EF
  kJointJump = 102,       // joint angle moved more in one tick than it physically can
  kJointStuck = 103,      // joint count frozen while the motor travelled far
  kMotorStuck = 111,      // motor count frozen under sustained duty
  // 200–299: limits
  kJointAngleLimit = 200,
  kMotorAngleLimit = 201,
  kTorqueLimit = 202,
  kVelocityLimit = 203,
  // 300–399: timing and communication
  kTickOverrun = 300,        // the previous tick did not finish in its period
  kCommandTimeout = 301,     // streamed setpoints stopped arriving
  kHostHeartbeatLost = 302,  // the supervising host went quiet during a motion
  kCanBusOff = 303,          // the CAN controller went bus-off: the host cannot stop us
  kBoardStartup = 304,       // the board did not come up whole (clock, encoder, CAN):
                             // held for the whole run, never cleared
  kEmergencyStop = 305,      // a host's StopAll (an emergency-stop button): every board
                             // stops, and stays stopped until a clear
};

// The faults the main loop raises (it sees the bus; the tick does not).
constexpr bool IsExternalFault(Fault f) {
  return f == Fault::kCommandTimeout || f == Fault::kHostHeartbeatLost ||
         f == Fault::kCanBusOff || f == Fault::kBoardStartup ||
         f == Fault::kEmergencyStop;
}

struct SupervisorConfig {
  Angle joint_min = Angle::FromDouble(-1.6);  // rad
  Angle joint_max = Angle::FromDouble(1.6);
  Angle motor_min = Angle::FromDouble(-2.0);  // motor-pulley rad
  Angle motor_max = Angle::FromDouble(2.0);
  Torque torque_max = Torque::FromDouble(1.0);  // |τ|, N·m
  // The joint's mean speed over the supervisor's velocity span (SetVelocitySpan), rad/s.
  AngularVelocity velocity_max = AngularVelocity::FromDouble(5.0);
  // Largest plausible joint step in one tick: 0.01 rad per 100 µs is 100 rad/s, twenty
  // times the velocity limit; a bigger step is a corrupted reading.
  Angle joint_jump_max = Angle::FromDouble(0.01);
  // Motor travel with the joint count frozen: the slack (≈ 2°) plus the full spring
  // deflection (0.2 N·m / 0.63 N·m/rad ≈ 0.32 rad) is under 0.4 rad; 0.6 rad cannot be.
  Angle stuck_motor_travel = Angle::FromDouble(0.6);
  // |duty| at or above this with the motor count frozen for motor_stuck_ticks, while the
  // position loop is more than stuck_hold_error off its setpoint: stalled motor or dead
  // encoder.
  Duty stuck_duty = Duty::FromDouble(0.3);
  std::uint32_t motor_stuck_ticks = 2000;  // 200 ms at 10 kHz
  // A motor the loop holds at its setpoint is not stalled, whatever duty the hold takes:
  // at rest the cable's static friction can keep it pressed on the pulley's slack edge,
  // and the pulley then holds up to α·0.3 N·m (duty 0.28 at α = 1, 0.34 at α = 1.25 on
  // the simulated joint), with the count still. A loop that settles on its setpoint ends
  // a few counts off it (8 counts here, 0.014°, its P term 0.01 duty); a stalled motor
  // or a dead encoder under a moving setpoint falls behind by more within milliseconds.
  Angle stuck_hold_error = Angle::FromDouble(2.5e-4);  // motor-pulley rad
};

// A SupervisorConfig's first invalid field. Stable numbers. A limit that no healthy
// sample can meet (an empty angle range, a limit at or below zero) would latch a fault
// on every tick; one that is never checked would hide a fault: both are refused.
enum class SupervisorConfigError : std::uint8_t {
  kOk = 0,
  kJointRange = 1,       // joint_min >= joint_max
  kMotorRange = 2,       // motor_min >= motor_max
  kTorqueMax = 3,        // <= 0
  kVelocityMax = 4,      // <= 0
  kJointJumpMax = 5,     // <= 0
  kStuckTravel = 6,      // <= 0
  kStuckDuty = 7,        // <= 0
  kMotorStuckTicks = 8,  // 0
  kStuckHoldError = 9,   // <= 0
};
SupervisorConfigError Validate(const SupervisorConfig& config);

// What the supervisor looks at each tick.
struct SupervisorInput {
  JointFrameStatus joint_status = JointFrameStatus::kOk;
  std::uint16_t joint_count = 0;  // raw 14-bit count of a good frame
  Angle joint;                    // θ_j of a good frame
  std::int64_t motor_count = 0;   // extended quadrature count
  Angle motor;                    // θ_m
  Torque torque;                  // SEA torque τ
  // θ_j − θ_j of the velocity span's ticks before (the last good readings at each): the
  // velocity limit judges the mean speed it implies (Supervisor::SetVelocitySpan).
  Angle joint_travel;
  Duty applied_duty;  // the duty applied over the previous tick
  Angle motor_error;  // the position loop's setpoint − θ_m behind that duty
  bool tick_overrun = false;
  // Raised by the main loop for this one tick (an event, not a condition: nothing is
  // left to clear afterwards). Only IsExternalFault() codes.
  Fault external = Fault::kNone;
};

class Supervisor {
 public:
  struct State {
    Fault latched = Fault::kNone;
    std::uint32_t fault_tick = 0;
    // Stuck and jump detection history.
    bool have_history = false;
    Angle last_joint;
    std::uint16_t last_joint_count = 0;
    Angle motor_at_joint_change;
    std::int64_t last_motor_count = 0;
    std::uint32_t motor_frozen_ticks = 0;
    void Clear() { *this = State{}; }
  };

  // The velocity limit stays at "any motion" (travel_max 0, which trips on the first
  // tick the joint moves) until SetVelocitySpan: forgetting it stops the motor rather
  // than leaving the limit unchecked.
  Supervisor(const SupervisorConfig* config, State* state)
      : config_(config), state_(state) {}

  // The velocity limit judges the joint's mean speed over the last `span_ticks` ticks,
  // |θ_j(n) − θ_j(n − span)| · tick_hz / span > velocity_max: a difference of two
  // readings, with no model and no filter, whose instant is span/2 ticks old. The
  // threshold on the travel, velocity_max · span / tick_hz, is taken here once; as
  // floor(v · 2^4 · span / tick_hz) in Angle LSBs (v in AngularVelocity LSBs) the
  // integer test |travel| > threshold is the exact rational one. Call after every
  // change of velocity_max, the span or the tick rate. A zero span or rate leaves the
  // limit at "any motion".
  void SetVelocitySpan(std::uint16_t span_ticks, std::uint32_t tick_hz);

  // Runs every check; latches and returns the first fault found (checked in the order
  // of the enum's ranges: sensors, limits, timing). Returns kNone while healthy, and
  // the latched fault once one is latched. Inlined, with Evaluate, into the tick: as
  // calls they cost it 13 Cortex-M4 instructions more (tick_instructions_cm4).
  Fault Check(std::uint32_t tick, const SupervisorInput& in);

  bool bridge_enabled() const { return state_->latched == Fault::kNone; }
  Fault latched() const { return state_->latched; }

  // The host's "clear faults": succeeds, and re-enables, only if `in` passes every
  // check that does not need history (sensor status, limits, timing). Jump and stuck
  // history restarts from `in`.
  bool Clear(const SupervisorInput& in);

 private:
  // A template so that each caller (Check with history, Clear without) gets its own
  // copy inlined: a call with the flag cost the tick 15 Cortex-M4 instructions more.
  template <bool kWithHistory>
  Fault Evaluate(const SupervisorInput& in) const;
  void Remember(const SupervisorInput& in);

  const SupervisorConfig* config_;
  State* state_;
  Angle travel_max_;  // SetVelocitySpan
};

template <bool kWithHistory>
[[gnu::always_inline]] inline Fault Supervisor::Evaluate(
    const SupervisorInput& in) const {
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
  if (Abs(in.joint_travel) > travel_max_) return Fault::kVelocityLimit;
  if (in.tick_overrun) return Fault::kTickOverrun;
  if (in.external != Fault::kNone) return in.external;
  return Fault::kNone;
}

inline void Supervisor::Remember(const SupervisorInput& in) {
  if (!state_->have_history || in.joint_count != state_->last_joint_count) {
    state_->motor_at_joint_change = in.motor;
  }
  state_->last_joint = in.joint;
  state_->last_joint_count = in.joint_count;
  state_->last_motor_count = in.motor_count;
  state_->have_history = true;
}

[[gnu::always_inline]] inline Fault Supervisor::Check(std::uint32_t tick,
                                                      const SupervisorInput& in) {
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

}  // namespace mjc
