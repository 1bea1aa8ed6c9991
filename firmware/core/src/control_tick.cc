#include "mjc/core/control_tick.h"

#include <span>

namespace mjc {

ControlTick::ControlTick()
    : motor_encoder_(&config_.motor_encoder, &motor_state_),
      backlash_(&config_.backlash, &backlash_state_),
      inverse_(&config_.backlash, &inverse_state_),
      windows_(config_.tick_hz),
      loop_(&config_.position, &loop_state_),
      supervisor_(&config_.supervisor, &supervisor_state_),
      estimator_(window_storage_) {
  Configure(config_);
}

ControlConfigError ControlTick::Validate(const ControlConfig& config) {
  if (config.tick_hz < 1000 || config.tick_hz > 20000)
    return ControlConfigError::kTickRate;
  if (ValidateMotorEncoderConfig(config.motor_encoder) != MotorEncoderConfigError::kOk) {
    return ControlConfigError::kMotorEncoder;
  }
  if (ValidateJointEncoderConfig(config.joint_encoder) != JointEncoderConfigError::kOk) {
    return ControlConfigError::kJointEncoder;
  }
  if (mjc::Validate(config.backlash) != BacklashConfigError::kOk) {
    return ControlConfigError::kBacklash;
  }
  if (!SeaStiffnessValid(config.sea_stiffness)) return ControlConfigError::kStiffness;
  const VelocityEstimatorConfig velocity{.window = config.velocity_window,
                                         .tick_hz = config.tick_hz};
  if (VelocityEstimator::Check(velocity, kMaxVelocityWindow) !=
      VelocityEstimatorError::kOk) {
    return ControlConfigError::kVelocityWindow;
  }
  PositionLoopConfig position = config.position;
  position.tick_hz = config.tick_hz;
  if (mjc::Validate(position) != PositionLoopError::kOk)
    return ControlConfigError::kPositionLoop;
  if (mjc::Validate(config.supervisor) != SupervisorConfigError::kOk) {
    return ControlConfigError::kSupervisor;
  }
  if (!AttachmentParamsValid(config.attachment_prior)) {
    return ControlConfigError::kAttachmentPrior;
  }
  return ControlConfigError::kOk;
}

CalibrationError Validate(const Calibration& calibration) {
  const BacklashConfigError backlash = Validate(calibration.backlash);
  if (backlash != BacklashConfigError::kOk) {
    return static_cast<CalibrationError>(backlash);
  }
  if (!SeaStiffnessValid(calibration.sea_stiffness)) return CalibrationError::kStiffness;
  if (calibration.joint_zero_count >= kJointCountsPerRev) {
    return CalibrationError::kJointZero;
  }
  return CalibrationError::kOk;
}

ControlConfigError ControlTick::Configure(const ControlConfig& config) {
  const ControlConfigError error = Validate(config);
  if (error != ControlConfigError::kOk) return error;
  estimator_.Configure({.window = config.velocity_window, .tick_hz = config.tick_hz});
  if (config.attachment_prior != config_.attachment_prior) {
    attachment_ = config.attachment_prior;
  }

  config_ = config;
  config_.position.tick_hz = config.tick_hz;
  motor_encoder_.Reconfigure();
  backlash_.Configure(config_.sea_stiffness);
  model_.Configure(config_.sea_stiffness, attachment_, config_.tick_hz);
  // The velocity limit's span is the ring's: θ_j of delay_ticks() ago is at hand.
  supervisor_.SetVelocitySpan(estimator_.delay_ticks(), config_.tick_hz);
  inverse_.Configure();
  loop_.Configure();
  windows_ = WindowTracker(config_.tick_hz);
  trajectory_ = TrajectoryGenerator(config_.tick_hz);
  Restart();
  return ControlConfigError::kOk;
}

void ControlTick::Restart() {
  started_ = false;
  backlash_state_.Clear();
  inverse_state_.Clear();
  loop_state_.Clear();
  supervisor_state_.Clear();
  windows_.Clear();
  energy_.Clear();
  supervised_.applied_duty = Duty{};
  supervised_.motor_error = Angle{};
}

bool ControlTick::SetAttachment(const AttachmentParams& params) {
  if (!model_.Configure(config_.sea_stiffness, params, config_.tick_hz)) return false;
  attachment_ = params;
  return true;
}

void ControlTick::Arm(bool armed) {
  if (armed && !armed_) loop_state_.Clear();  // no stale integral on enable
  armed_ = armed;
}

void ControlTick::ISR_Step(const Sample& sample, TickResult* out) {
  TickResult& r = *out;
  Telemetry& t = r.telemetry;
  r.raised = Fault::kNone;

  // 1. Sensors.
  if (!motor_started_) {
    motor_encoder_.Reset(sample.motor_count);
    motor_started_ = true;
  }
  const Angle motor = motor_encoder_.Update(sample.motor_count);
  const JointSample joint_sample =
      DecodeJointFrame(sample.joint_frame, config_.joint_encoder);
  if (joint_sample.status == JointFrameStatus::kOk) {
    supervised_.joint = joint_sample.angle;
    supervised_.joint_count = joint_sample.count;
  }
  if (!started_) {
    backlash_.Reset(motor, supervised_.joint);
    // The play operator gives the same θ̃_j again for the same inputs (step 2).
    model_.Reset(supervised_.joint, backlash_.Update(motor, supervised_.joint));
    estimator_.Reset(Angle{});  // θ_j − θ_model: the model starts at θ_j
    // Every slot of the ring in use (the estimator's delay, >= 16 ticks: Validate).
    for (std::size_t i = 0; i < estimator_.delay_ticks(); ++i) {
      delayed_[i] = {.torque = 0,
                     .joint = supervised_.joint.raw(),
                     .model_step = 0,
                     .segment = Segment::kIdle,
                     .repetition = 0};
    }
    delayed_next_ = 0;
    started_ = true;
  }

  // 2. Cable side and SEA torque (eqs. 4, 5). The joint angle in a local: read through
  // the member, it was loaded again after each store through the models' state
  // pointers (which might alias it), 2 Cortex-M4 instructions a tick.
  const Angle joint = supervised_.joint;
  const Angle cable = backlash_.Update(motor, joint);
  const Torque torque = Mul<Torque>(config_.sea_stiffness, cable - joint);

  // 3.–4. Aligned velocity, torque, angle and segment; power and energy (eq. 3). The
  // slope is of θ_j less the model at the middle of its step (the mean of its states
  // before and after), and the step at the centre is added back: the model's velocity
  // at that same half tick (attachment_model.h).
  const std::int32_t model_step = model_.ISR_Step(cable);
  // θ_before + θ_after in ModelAngle raw, halved into Angle raw: two states within
  // ±6 rad add up within ModelAngle's ±16 rad (attachment_model.h).
  constexpr int kMidShift = ModelAngle::kFracBits - Angle::kFracBits + 1;
  const std::int32_t model_mid =
      (2 * model_.angle().raw() - model_step + (1 << (kMidShift - 1))) >> kMidShift;
  Delayed& delayed = delayed_[delayed_next_];
  // |θ_j| ≤ π and |θ_model| ≤ 6 rad: the residual fits Angle without a saturation test.
  const AngularVelocity velocity =
      estimator_.Update(Angle::FromRaw(joint.raw() - model_mid), delayed.model_step);
  const Torque aligned_torque = Torque::FromRaw(delayed.torque);
  const Angle aligned_joint = Angle::FromRaw(delayed.joint);
  delayed.torque = torque.raw();
  delayed.joint = joint.raw();
  delayed.model_step = model_step;
  const Power power = Mul<Power>(aligned_torque, velocity);
  energy_.Add(power);

  // 5. Supervisor, before any duty is computed. Its input lives in the tick
  // (supervised_): what persists between ticks is written where it changes (the last
  // good joint reading above, the duty and its error below, an external fault when
  // raised), so only this tick's readings are stored here; a SupervisorInput built
  // whole each tick cost 8 Cortex-M4 instructions more (tick_instructions_cm4).
  supervised_.joint_status = joint_sample.status;
  supervised_.motor_count = motor_encoder_.extended_count();
  supervised_.motor = motor;
  supervised_.torque = torque;
  // The velocity limit judges the joint's own travel over the ring's span (the
  // supervisor's mean speed), not the aligned estimate: no model in it, and its instant
  // is half as old (supervisor.h).
  supervised_.joint_travel = joint - aligned_joint;
  supervised_.tick_overrun = sample.tick_overrun;
  r.clear = FaultClear::kNone;
  if (clear_requested_) {
    clear_requested_ = false;
    if (!supervisor_.bridge_enabled()) {
      r.clear =
          supervisor_.Clear(supervised_) ? FaultClear::kCleared : FaultClear::kRefused;
    }
  }
  const bool was_healthy = supervisor_.bridge_enabled();
  const Fault fault = supervisor_.Check(tick_, supervised_);
  supervised_.external = Fault::kNone;  // an event: this tick's checks saw it
  if (was_healthy && fault != Fault::kNone) {
    r.raised = fault;
    trajectory_.Stop();
  }

  // 6. Trajectory and position loop.
  const TrajectoryPoint point = trajectory_.Step();
  const Segment aligned_segment = delayed.segment;
  const std::uint16_t aligned_repetition = delayed.repetition;
  delayed.segment = point.segment;
  delayed.repetition = point.repetition;
  delayed_next_ = delayed_next_ + 1 == estimator_.delay_ticks() ? 0 : delayed_next_ + 1;
  const std::uint32_t aligned_tick = tick_ - estimator_.delay_ticks();
  r.window_completed =
      windows_.Update(aligned_tick, aligned_segment, aligned_repetition, power,
                      aligned_torque, aligned_joint, velocity, &r.window, &r.window_fit);

  const Angle setpoint =
      config_.backlash_compensation ? inverse_.Command(point.position) : point.position;
  const bool enabled = armed_ && supervisor_.bridge_enabled();
  Duty duty;
  if (enabled) {
    duty = loop_.Update(setpoint, point.velocity, motor);
  } else {
    loop_state_.Clear();
  }
  supervised_.applied_duty = duty;
  supervised_.motor_error = enabled ? setpoint - motor : Angle{};
  r.actuation = {duty, enabled};

  t.tick = tick_;
  t.motor = motor;
  t.joint = supervised_.joint;
  t.cable_side = cable;
  t.torque = torque;
  t.setpoint = setpoint;
  t.duty = duty;
  t.joint_velocity = velocity;
  t.aligned_torque = aligned_torque;
  t.power = power;
  t.energy_sum = energy_.raw_sum();
  t.segment = point.segment;
  t.fault = supervisor_.latched();
  ++tick_;
}

}  // namespace mjc
