// One control tick of the joint board (docs/DESIGN.md §2): the unit the firmware's timer
// ISR and the simulated board call at 10 kHz. Sample in, actuation out, plus telemetry
// and events. No allocation, no blocking, no HAL: the caller reads the hardware into a
// Sample and writes the Actuation back.
//
// Order within a tick, so that a fault disables the bridge in the tick that sees it:
//   1 sample → θ_m (quadrature extension), θ_j (SPI frame, parity checked)
//   2 forward backlash → θ̃_j;  SEA torque τ = K(θ̃_j − θ_j)
//   3 velocity θ̇_j: the attachment model follows θ̃_j (attachment_model.h); the
//     least-squares slope of θ_j − θ_model (delay L) plus the model's own velocity;
//     τ, θ_j and the trajectory segment are delayed by the same L, so P = τ·θ̇_j and its
//     window refer to one instant
//   4 P into the energy accumulator and the window tracker
//   5 supervisor: any fault → bridge off now, latched (the velocity limit on θ_j's
//     travel over the last L ticks: the ring's oldest θ_j, not the aligned estimate)
//   6 trajectory → setpoint (→ inverse backlash if enabled) → position loop → duty
// Cost on Cortex-M4: `./bench` prints tick_instructions_cm4.
#pragma once

#include <array>
#include <cstdint>

#include "mjc/core/attachment_model.h"
#include "mjc/core/backlash.h"
#include "mjc/core/encoder.h"
#include "mjc/core/interface_energy.h"
#include "mjc/core/position_loop.h"
#include "mjc/core/quantities.h"
#include "mjc/core/supervisor.h"
#include "mjc/core/tick_io.h"
#include "mjc/core/trajectory.h"
#include "mjc/core/velocity_estimator.h"

namespace mjc {

struct ControlConfig {
  std::uint32_t tick_hz = 10000;  // 1,000..20,000
  MotorEncoderConfig motor_encoder;
  JointEncoderConfig joint_encoder;
  BacklashConfig backlash;
  // 2·k·r_j², N·m/rad: (0, 100]. Paper magnitude 0.63.
  Stiffness sea_stiffness = Stiffness::FromDouble(0.63);
  // Command the cable side through the inverse backlash model instead of the motor.
  bool backlash_compensation = false;
  // Velocity window, ticks: odd, up to kMaxVelocityWindow. 1001 at 10 kHz: a 50 ms
  // delay, the longest the power estimate may lag (SIGNAL_CHAIN.md).
  std::uint16_t velocity_window = 1001;
  // The attachment the velocity estimator's model assumes until the board's own fit of
  // a window replaces it (AttachmentParamsValid; attachment_model.h). A typical finger:
  // k 4.5 N·m/rad, b 0.25 N·m·s/rad; a model 45 % off still serves.
  AttachmentParams attachment_prior{Stiffness::FromDouble(4.5),
                                    Damping::FromDouble(0.25)};
  PositionLoopConfig position;  // its tick_hz is ignored: tick_hz above applies
  SupervisorConfig supervisor;
};

// SEA stiffness 2·k·r_j² a config or a calibration may carry: (0, 100] N·m/rad.
constexpr bool SeaStiffnessValid(Stiffness k) {
  return k > Stiffness{} && k <= Stiffness(100);
}

// What a calibration sets (docs/DESIGN.md §5): the backlash model, the SEA stiffness and
// the joint encoder's zero. The rest of ControlConfig is configuration, not calibration.
struct Calibration {
  BacklashConfig backlash;
  Stiffness sea_stiffness = ControlConfig{}.sea_stiffness;
  std::uint16_t joint_zero_count = 0;  // [0, kJointCountsPerRev)

  // `config` with this calibration's fields.
  ControlConfig AppliedTo(ControlConfig config) const {
    config.backlash = backlash;
    config.sea_stiffness = sea_stiffness;
    config.joint_encoder.zero_offset = joint_zero_count;
    return config;
  }
};

// A calibration's first invalid field. Stable numbers: the detail of a refused
// calibration, sent to the host. 1..15 are the BacklashConfigError, passed through.
enum class CalibrationError : std::uint8_t {
  kOk = 0,
  kStiffness = 100,  // outside SeaStiffnessValid
  kJointZero = 101,  // >= kJointCountsPerRev
};
CalibrationError Validate(const Calibration& calibration);

// Why a config was refused; the previous config stays. Stable numbers.
enum class ControlConfigError : std::uint8_t {
  kOk = 0,
  kTickRate = 1,
  kMotorEncoder = 2,
  kJointEncoder = 3,
  kBacklash = 4,
  kStiffness = 5,
  kVelocityWindow = 6,
  kPositionLoop = 7,
  kSupervisor = 8,
  kAttachmentPrior = 9,  // outside AttachmentParamsValid
};

struct Telemetry {
  std::uint32_t tick = 0;
  Angle motor;       // θ_m
  Angle joint;       // θ_j (last good frame)
  Angle cable_side;  // θ̃_j
  Torque torque;     // τ, this tick
  Angle setpoint;    // motor setpoint commanded this tick
  Duty duty;
  // Aligned signals, delay_ticks() old: the instant power and energy refer to.
  AngularVelocity joint_velocity;
  Torque aligned_torque;
  Power power;
  std::int64_t energy_sum = 0;       // Σ P (raw Q24 W·ticks) since the last Configure()
  Segment segment = Segment::kIdle;  // of this tick's setpoint
  Fault fault = Fault::kNone;        // latched fault, kNone when healthy
};

// The outcome of a clear requested with RequestClearFaults().
enum class FaultClear : std::uint8_t { kNone = 0, kCleared = 1, kRefused = 2 };

struct TickResult {
  Actuation actuation;
  Telemetry telemetry;
  bool window_completed = false;  // `window` and `window_fit` hold a new summary
  WindowSummary window;
  InterfaceFitSums window_fit;           // the window's sums for the attachment's fit
  Fault raised = Fault::kNone;           // a fault latched in this very tick
  FaultClear clear = FaultClear::kNone;  // a requested clear, judged on this sample
};

class ControlTick {
 public:
  // 100 ms at 10 kHz: the longest velocity window the storage holds.
  static constexpr std::uint16_t kMaxVelocityWindow = 1001;

  ControlTick();

  // Validates every part and applies the config; on error nothing changes. Clears the
  // tick's state (the next Step() starts from its sample).
  ControlConfigError Configure(const ControlConfig& config);

  // The validation Configure() applies, without a ControlTick (for the main loop, which
  // refuses a config before handing it to the tick).
  static ControlConfigError Validate(const ControlConfig& config);

  // Runs one tick (interrupt context). Writes every field of *out except `window` and
  // `window_fit`, which are written only when window_completed is set: the summary is not
  // copied or cleared on the other ticks.
  void ISR_Step(const Sample& sample, TickResult* out);

  // Bridge permission from the application (idle vs running): the bridge is enabled
  // only while armed and no fault is latched.
  void Arm(bool armed);
  bool armed() const { return armed_; }

  // Asks the next ISR_Step to clear a latched fault if that tick's own sample shows the
  // cause gone (judged before any duty is computed); the outcome is in its
  // TickResult::clear.
  void RequestClearFaults() { clear_requested_ = true; }
  // A fault seen outside the tick (IsExternalFault: the setpoint stream or the host
  // went quiet, the bus went off): the next ISR_Step latches it and stops the motor.
  // An event, not a condition: nothing is left to clear afterwards. Other codes are
  // ignored.
  void RaiseExternalFault(Fault fault) {
    if (IsExternalFault(fault)) supervised_.external = fault;
  }
  Fault fault() const { return supervisor_.latched(); }

  // The attachment the velocity estimator's model now follows (tick context): a valid
  // fit of a window (the main loop solves it) replaces the prior. False, changing
  // nothing, outside AttachmentParamsValid. Kept through Configure() unless the
  // config's prior changes.
  bool SetAttachment(const AttachmentParams& params);
  const AttachmentParams& attachment() const { return attachment_; }

  TrajectoryGenerator& trajectory() { return trajectory_; }
  std::uint16_t delay_ticks() const { return estimator_.delay_ticks(); }
  EnergyScale energy_scale() const { return EnergyScale(config_.tick_hz); }
  const ControlConfig& config() const { return config_; }

 private:
  void Restart();

  ControlConfig config_;
  MotorEncoderState motor_state_;
  MotorEncoder motor_encoder_;
  BacklashModel::State backlash_state_;
  BacklashModel backlash_;
  InverseBacklash::State inverse_state_;
  InverseBacklash inverse_;
  std::size_t delayed_next_ = 0;  // [0, delay_ticks())
  // The prior of the config in force until a fit replaces it (SetAttachment).
  AttachmentParams attachment_ = ControlConfig{}.attachment_prior;
  AttachmentModel model_;
  EnergyAccumulator energy_;
  WindowTracker windows_;
  TrajectoryGenerator trajectory_;
  PositionLoop::State loop_state_;
  PositionLoop loop_;
  Supervisor::State supervisor_state_;
  Supervisor supervisor_;

  // Counts every tick since construction, across reconfigurations: the board's clock
  // (telemetry, window ticks, the CAN side's schedules and timeouts).
  std::uint32_t tick_ = 0;
  bool clear_requested_ = false;
  bool started_ = false;
  // The motor count is extended from the first tick since construction and never
  // restarted: the quadrature timer keeps counting through a reconfiguration, and
  // restarting from its raw unsigned value would read a pulley at −0.1 rad as +1.9.
  bool motor_started_ = false;
  bool armed_ = false;
  // The supervisor's input (ISR_Step, step 5), holding between ticks the last good
  // θ_j and its count, the duty applied and the position loop's setpoint − θ_m behind
  // it, and an external fault raised since the last tick.
  SupervisorInput supervised_;
  // The two rings last: 12 KB that, anywhere earlier, would put every member after them
  // out of reach of a load's immediate offset (4 KB on the Cortex-M4), each access an
  // address computation more (tick_instructions_cm4). The estimator is reached
  // through its own `this`.
  std::array<std::int32_t, kMaxVelocityWindow> window_storage_{};
  VelocityEstimator estimator_;  // after its storage, which it keeps a span of
  // What waits delay_ticks() to meet the velocity estimate of its instant: each tick's
  // torque, joint angle, model step and trajectory segment, in one ring with one index
  // (as two DelayLines the tick spent 11 Cortex-M4 instructions more, mostly on the
  // second index; tick_instructions_cm4).
  // The torque, angle and step are taken out and put in at step 3, the segment at
  // step 6, then the index moves on.
  struct Delayed {
    std::int32_t torque = 0;      // Torque raw
    std::int32_t joint = 0;       // θ_j, Angle raw
    std::int32_t model_step = 0;  // the attachment model's step, ModelAngle raw
    Segment segment = Segment::kIdle;
    std::uint16_t repetition = 0;
  };
  std::array<Delayed, kMaxVelocityWindow / 2> delayed_{};
};

}  // namespace mjc
