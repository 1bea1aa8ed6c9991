#include "mjc/app/joint_app.h"

namespace mjc::app {

JointApp::JointApp(const ControlConfig& config) { control_.Configure(config); }

CommandOutcome JointApp::Submit(const Command& command) {
  if (!commands_.ISR_Push(command)) return {CommandResult::kRefusedBusy, 0};
  return {};
}

CommandOutcome JointApp::Configure(const ControlConfig& config) {
  if (state_ != AppState::kIdle) return {CommandResult::kRefusedNotIdle, 0};
  Command c;
  c.kind = CommandKind::kConfigure;
  c.config = config;
  return Submit(c);
}

// Validated here, merged into the running config in the tick: `full` also takes the
// SEA stiffness and the joint encoder's zero from `calibration`.
CommandOutcome JointApp::SubmitCalibration(const ControlConfig& calibration, bool full) {
  if (state_ != AppState::kIdle) return {CommandResult::kRefusedNotIdle, 0};
  const BacklashConfigError error = Validate(calibration.backlash);
  if (error != BacklashConfigError::kOk) {
    return {CommandResult::kRefusedInvalid, static_cast<std::uint8_t>(error)};
  }
  Command c;
  c.kind = CommandKind::kSetCalibration;
  c.config = calibration;
  c.full_calibration = full;
  return Submit(c);
}

CommandOutcome JointApp::SetCalibration(const BacklashConfig& backlash) {
  ControlConfig calibration;
  calibration.backlash = backlash;
  return SubmitCalibration(calibration, false);
}

CommandOutcome JointApp::SetCalibration(const BacklashConfig& backlash,
                                        Stiffness sea_stiffness,
                                        std::uint16_t joint_zero_count) {
  ControlConfig calibration;
  calibration.backlash = backlash;
  calibration.sea_stiffness = sea_stiffness;
  calibration.joint_encoder.zero_offset = joint_zero_count;
  return SubmitCalibration(calibration, true);
}

CommandOutcome JointApp::StartTrial(const SineConfig& sine) {
  if (state_ != AppState::kIdle) return {CommandResult::kRefusedNotIdle, 0};
  if (!calibrated_) return {CommandResult::kRefusedUncalibrated, 0};
  const TrajectoryError error = Validate(sine);
  if (error != TrajectoryError::kOk) {
    return {CommandResult::kRefusedInvalid, static_cast<std::uint8_t>(error)};
  }
  Command c;
  c.kind = CommandKind::kStartTrial;
  c.sine = sine;
  return Submit(c);
}

CommandOutcome JointApp::StartCalibrationSweep(const SweepConfig& sweep) {
  if (state_ != AppState::kIdle) return {CommandResult::kRefusedNotIdle, 0};
  const TrajectoryError error = Validate(sweep);
  if (error != TrajectoryError::kOk) {
    return {CommandResult::kRefusedInvalid, static_cast<std::uint8_t>(error)};
  }
  Command c;
  c.kind = CommandKind::kStartSweep;
  c.sweep = sweep;
  return Submit(c);
}

CommandOutcome JointApp::StartStream(AngularVelocity max_rate) {
  if (state_ != AppState::kIdle) return {CommandResult::kRefusedNotIdle, 0};
  if (!calibrated_) return {CommandResult::kRefusedUncalibrated, 0};
  if (max_rate.raw() <= 0) {
    return {CommandResult::kRefusedInvalid,
            static_cast<std::uint8_t>(TrajectoryError::kRateNotPositive)};
  }
  Command c;
  c.kind = CommandKind::kStartStream;
  c.stream_rate = max_rate;
  return Submit(c);
}

void JointApp::ISR_FollowStream() {
  if (control_.trajectory().mode() != TrajectoryMode::kStream) return;
  const std::int32_t target = stream_target_.load(std::memory_order_relaxed);
  if (target == applied_stream_target_) return;
  applied_stream_target_ = target;
  (void)control_.trajectory().SetStreamTarget(Angle::FromRaw(target));
}

CommandOutcome JointApp::Stop() {
  Command c;
  c.kind = CommandKind::kStop;
  return Submit(c);
}

CommandOutcome JointApp::ClearFaults() {
  Command c;
  c.kind = CommandKind::kClearFaults;
  return Submit(c);
}

void JointApp::ISR_Refuse(CommandResult result, std::uint8_t detail) {
  AppEvent e;
  e.kind = AppEvent::Kind::kCommandRefused;
  e.tick = result_.telemetry.tick;
  e.state = state_;
  e.refusal = {result, detail};
  events_.ISR_Push(e);
}

void JointApp::ISR_Enter(AppState next) {
  if (next == state_) return;
  state_ = next;
  control_.Arm(next == AppState::kRunning || next == AppState::kCalibrating);
  AppEvent e;
  e.kind = AppEvent::Kind::kStateChanged;
  e.tick = result_.telemetry.tick;
  e.state = next;
  events_.ISR_Push(e);
}

void JointApp::ISR_ApplyCommand() {
  Command c;
  if (!commands_.Pop(&c)) return;
  const bool idle = state_ == AppState::kIdle;
  switch (c.kind) {
    case CommandKind::kConfigure:
    case CommandKind::kSetCalibration: {
      if (!idle) return ISR_Refuse(CommandResult::kRefusedNotIdle);
      if (c.kind == CommandKind::kSetCalibration) {
        const ControlConfig calibration = c.config;
        c.config = control_.config();
        c.config.backlash = calibration.backlash;
        if (c.full_calibration) {
          c.config.sea_stiffness = calibration.sea_stiffness;
          c.config.joint_encoder.zero_offset = calibration.joint_encoder.zero_offset;
        }
      }
      const ControlConfigError error = control_.Configure(c.config);
      if (error != ControlConfigError::kOk) {
        return ISR_Refuse(CommandResult::kRefusedInvalid,
                          static_cast<std::uint8_t>(error));
      }
      if (c.kind == CommandKind::kSetCalibration) calibrated_ = true;
      return;
    }
    case CommandKind::kStartTrial:
    case CommandKind::kStartSweep: {
      if (!idle) return ISR_Refuse(CommandResult::kRefusedNotIdle);
      const bool trial = c.kind == CommandKind::kStartTrial;
      if (trial && !calibrated_) return ISR_Refuse(CommandResult::kRefusedUncalibrated);
      const TrajectoryError error = trial ? control_.trajectory().StartSine(c.sine)
                                          : control_.trajectory().StartSweep(c.sweep);
      if (error != TrajectoryError::kOk) {
        return ISR_Refuse(CommandResult::kRefusedInvalid,
                          static_cast<std::uint8_t>(error));
      }
      return ISR_Enter(trial ? AppState::kRunning : AppState::kCalibrating);
    }
    case CommandKind::kStartStream: {
      if (!idle) return ISR_Refuse(CommandResult::kRefusedNotIdle);
      if (!calibrated_) return ISR_Refuse(CommandResult::kRefusedUncalibrated);
      // From where the motor is (idle, the bridge was off and it may have moved): no
      // jump on the first streamed tick; it holds there until targets arrive.
      const Angle from = result_.telemetry.motor;
      const TrajectoryError error =
          control_.trajectory().StartStream(from, c.stream_rate);
      if (error != TrajectoryError::kOk) {
        return ISR_Refuse(CommandResult::kRefusedInvalid,
                          static_cast<std::uint8_t>(error));
      }
      applied_stream_target_ = from.raw();
      stream_target_.store(from.raw(), std::memory_order_relaxed);
      return ISR_Enter(AppState::kRunning);
    }
    case CommandKind::kStop:
      control_.trajectory().Stop();
      if (state_ != AppState::kFault) ISR_Enter(AppState::kIdle);
      return;
    case CommandKind::kClearFaults:
      // Judged in this tick's step, on this tick's sample (ISR_AfterStep).
      if (state_ == AppState::kFault) control_.RequestClearFaults();
      return;
  }
}

void JointApp::ISR_AfterStep() {
  if (result_.clear == FaultClear::kCleared && result_.raised == Fault::kNone) {
    ISR_Enter(AppState::kIdle);
  } else if (result_.clear == FaultClear::kRefused) {
    ISR_Refuse(CommandResult::kRefusedFaultActive);
  }
  if (result_.raised != Fault::kNone) {
    AppEvent e;
    e.kind = AppEvent::Kind::kFault;
    e.tick = result_.telemetry.tick;
    e.fault = result_.raised;
    events_.ISR_Push(e);
    ISR_Enter(AppState::kFault);
  }
  if (result_.window_completed) {
    AppEvent e;
    e.kind = AppEvent::Kind::kWindow;
    e.tick = result_.telemetry.tick;
    e.state = state_;
    e.window = result_.window;
    events_.ISR_Push(e);
  }
  const bool moving = state_ == AppState::kRunning || state_ == AppState::kCalibrating;
  if (moving && result_.telemetry.segment == Segment::kIdle) ISR_Enter(AppState::kIdle);
}

}  // namespace mjc::app
