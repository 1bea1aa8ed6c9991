// Every fault the board stops for, injected at its real cause in the simulated board,
// with the time from the cause to the first tick that writes a disabled bridge. Shared
// by tests/sim/fault_stop_test.cc (the goals, asserted) and tests/bench/safe_stop.cc
// (the safe_stop_ticks_* figures of ./bench).
//
// Each case runs the unmodified firmware — JointApp and CanNode on SimBoard, the plant
// wearing subject1's hand, noise on — under a host on an in-process bus: calibrated
// (the plant's own slack offsets, as tests/sim/bus_trial_test.cc does), a 25° 0.5 Hz
// trial started with TrialConfig + StartTrial frames (a setpoint stream for the command
// timeout), host heartbeats at 10 Hz. The main loop around each tick is the firmware's:
// received frames handled, the tick, CanNode::Poll, the transmit queue drained.
//
// The cause, and the tick the time is counted from (ticks are the board's own
// telemetry tick numbers):
//   joint_parity, joint_error_flag   plant joint fault, until cleared; from the tick
//                                    whose sample carries the corrupted frame
//   joint_jump                       plant joint fault, one read offset by 100 counts
//                                    (0.038 rad, 38× joint_jump_max); from that sample
//   joint_stuck, motor_stuck         plant encoder frozen, until cleared; from the first
//                                    frozen sample. A frozen count looks like a joint or
//                                    motor at rest, so the supervisor's rules need
//                                    evidence first (joint: the motor travelled
//                                    stuck_motor_travel since the count last changed;
//                                    motor: motor_stuck_ticks frozen under stuck_duty);
//                                    `detectable_tick` is the first sample meeting the
//                                    rule, evaluated here on the raw samples
//   joint_angle_limit, motor_angle_limit, velocity_limit
//                                    the limit is lowered in the board's config below
//                                    what the trial reaches on the way to its first
//                                    flexion peak, and the trial crosses it physically
//   torque_limit                     the host lowers the limit to 0.15 N·m over the bus
//                                    (ParamWrite) and the subject resists the flexion
//                                    (the strap preload ramps to 1 N·m); the load keeps
//                                    the spring beyond the limit after the stop
//                                    Angles and torque: from the first sample beyond
//                                    the limit, judged by a double reference on the raw
//                                    sample words (joint frame, extended motor count,
//                                    play operator with the uploaded calibration,
//                                    K·(θ̃ − θ_j)). Velocity: from the first sample
//                                    instant whose plant-truth joint velocity exceeds
//                                    the limit. The board judges the joint's mean
//                                    speed over the last delay_ticks() ticks (its
//                                    travel over that span), whose middle is half the
//                                    span back, so this stop is not 0 ticks;
//                                    `detectable_tick` is where that mean, recomputed
//                                    in double on the raw joint frames, first comes
//                                    within kVelocityReferenceTolRadS of the limit
//   tick_overrun                     SimJointIo::InjectOverrun before every tick until
//                                    the cause is removed (a tick that keeps running
//                                    late); from the first late sample
//   command_timeout                  the host stops streaming setpoints (heartbeats go
//                                    on); from the board tick at which the last
//                                    Setpoint was received
//   host_heartbeat_lost              the host goes quiet during the trial; from the
//                                    board tick at which the last HostHeartbeat was
//                                    received
//   can_bus_off                      CanNode::OnBusOff() from the main loop; from the
//                                    board tick of that call. For the recovery (128 × 11
//                                    recessive bits at 1 Mbit/s, 15 ticks) nothing is
//                                    delivered either way.
//   emergency_stop                   the host broadcasts a StopAll (node 0: mjc estop);
//                                    from the board tick after which the main loop
//                                    received it
//
// After the stop each case checks, through the bus: the FaultEvent decodes with the
// stable code and the stop tick; the bridge stays off on every tick until an accepted
// ClearFaults; where the cause can persist (parity, EF, overrun, the limits) a
// ClearFaults while the reference shows it present is refused; then the subject
// relaxes (torque_limit), the operator brings the joint back to rest by hand (the
// motor pulley moved kinematically to 0 with the bridge off), the sensor recovers
// (Plant::ClearFaults), and a ClearFaults with the reference showing the cause gone
// returns the board to idle.
//
// No refused clear is tried for lost messages, bus-off and the emergency stop (events:
// the board cannot see a button still pressed; mjc estop sends the stop again while it
// is; nothing is left to
// clear) nor for a frozen encoder: the supervisor's Clear() re-runs only the checks
// that need no history, so it accepts a clear while an encoder is still frozen (a
// frozen count is only implausible under motion; the fault returns once motion makes
// it so again).
#pragma once

#include <array>
#include <cstdint>
#include <string>

#include "mjc/core/supervisor.h"
#include "mjc/protocol/messages.h"

namespace mjc::safe_stop {

enum class FaultCase : std::uint8_t {
  kJointParity,
  kJointErrorFlag,
  kJointJump,
  kJointStuck,
  kMotorStuck,
  kJointAngleLimit,
  kMotorAngleLimit,
  kTorqueLimit,
  kVelocityLimit,
  kTickOverrun,
  kCommandTimeout,
  kHostHeartbeatLost,
  kCanBusOff,
  kEmergencyStop,
};

inline constexpr std::array<FaultCase, 14> kAllCases = {
    FaultCase::kJointParity,     FaultCase::kJointErrorFlag,
    FaultCase::kJointJump,       FaultCase::kJointStuck,
    FaultCase::kMotorStuck,      FaultCase::kJointAngleLimit,
    FaultCase::kMotorAngleLimit, FaultCase::kTorqueLimit,
    FaultCase::kVelocityLimit,   FaultCase::kTickOverrun,
    FaultCase::kCommandTimeout,  FaultCase::kHostHeartbeatLost,
    FaultCase::kCanBusOff,       FaultCase::kEmergencyStop,
};

// snake_case, as in the figure names (safe_stop_ticks_<name>).
const char* Name(FaultCase c);
// The supervisor's code the case must latch.
Fault ExpectedFault(FaultCase c);

// How far the mean speed the board judges may lie from the double-precision
// reference's: the board's two θ_j are each Angle-rounded (±0.5 LSB, 2^-24 rad), so
// their difference is within 1 LSB, 1.2e-6 rad/s over the 500-tick span at 10 kHz; the
// comparison with the limit is exact (supervisor.h). The velocity rule's detectable
// tick is where the reference first comes within this of the limit.
inline constexpr double kVelocityReferenceTolRadS = 2e-6;
inline constexpr double kVelocityMaxRadS = 0.1;

struct Measurement {
  FaultCase which = FaultCase::kJointParity;
  // Empty when the scenario ran as planned (motion started, the bridge went off, the
  // frames arrived); otherwise what went wrong, and the fields below are partial.
  std::string error;

  std::uint32_t tick_hz = 0;
  std::uint32_t cause_tick = 0;       // see the table above
  std::uint32_t detectable_tick = 0;  // stuck: first sample meeting the rule; else cause
  std::uint32_t stop_tick = 0;        // first tick whose written actuation is disabled
  Fault raised = Fault::kNone;        // what the board latched in the stop tick
  std::uint16_t delay_ticks = 0;      // the velocity estimator's delay: the limit's span
  // The reference's |mean speed| on the tick before the stop and on the stop's tick.
  double velocity_before_stop = 0;
  double velocity_at_stop = 0;
  double truth_mean_at_stop = 0;  // the plant's mean joint speed over that span then
  std::uint16_t host_timeout_ms = 0;
  std::uint16_t stream_timeout_ms = 0;

  // The FaultEvent frame(s) from the board, decoded with the protocol's Decode.
  int fault_frames = 0;
  Fault frame_fault = Fault::kNone;
  std::uint32_t frame_tick = 0;

  // The bridge was off (and the app in kFault) on each of `latched_ticks` ticks from
  // the stop up to the tick that judged the accepted clear.
  bool latched = false;
  std::uint32_t latched_ticks = 0;

  // A ClearFaults sent while the cause persists (cases where it can).
  bool refusal_tried = false;
  bool cause_present_at_refusal = false;  // the reference, on the judging tick's sample
  protocol::CommandOutcomeCode refusal_outcome = protocol::CommandOutcomeCode::kAccepted;
  bool fault_after_refusal = false;  // still kFault, bridge off

  // The ClearFaults after the cause is gone.
  bool cause_gone_at_clear = false;  // the reference, on the judging tick's sample
  bool clear_answered = false;
  protocol::CommandOutcomeCode clear_outcome = protocol::CommandOutcomeCode::kRefusedBusy;
  bool idle_after_clear = false;

  // Ticks from the cause to the disabled bridge, and in ms.
  std::int64_t stop_ticks() const {
    return std::int64_t{stop_tick} - std::int64_t{cause_tick};
  }
  std::int64_t detect_to_stop_ticks() const {
    return std::int64_t{stop_tick} - std::int64_t{detectable_tick};
  }
  double stop_ms() const {
    return 1000.0 * static_cast<double>(stop_ticks()) / static_cast<double>(tick_hz);
  }
};

// Runs one case from power-on; deterministic (every seed constant). A few hundred ms
// of wall time.
Measurement Measure(FaultCase c);

}  // namespace mjc::safe_stop
