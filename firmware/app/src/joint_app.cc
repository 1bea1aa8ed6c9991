#include "mjc/app/joint_app.h"

#include <algorithm>

namespace mjc::app {
namespace {

template <class Error>
CommandOutcome Invalid(Error e) {
  return {CommandOutcomeCode::kRefusedInvalid, static_cast<std::uint8_t>(e)};
}

}  // namespace

JointApp::JointApp(const ControlConfig& config) {
  control_.Configure(config);
  main_config_ = control_.config();
}

const ControlConfig& JointApp::config() const {
  const std::uint32_t generation = config_generation_.load(std::memory_order_acquire);
  if (generation != main_generation_) {
    // The tick may apply yet another one during the copy: the copy is taken again then.
    main_config_ = done_.Read([this] { return control_.config(); });
    main_generation_ = generation;
  }
  return main_config_;
}

CommandOutcome JointApp::Submit(const Request& request) {
  if (!requests_.Push(request)) return {CommandOutcomeCode::kRefusedBusy, 0};
  return {};
}

CommandOutcome JointApp::CheckStart(bool needs_calibration, BoardState state,
                                    bool calibrated) {
  if (state != BoardState::kIdle) return {CommandOutcomeCode::kRefusedNotIdle, 0};
  if (needs_calibration && !calibrated)
    return {CommandOutcomeCode::kRefusedUncalibrated, 0};
  return {};
}

CommandOutcome JointApp::CheckStart(bool needs_calibration) const {
  const Snapshot last = Latest();
  return CheckStart(needs_calibration, last.state, last.calibrated);
}

CommandOutcome JointApp::Submit(RequestKind kind, RequestTag tag) {
  Request c;
  c.kind = kind;
  c.tag = tag;
  return Submit(c);
}

template <class Error, class T>
CommandOutcome JointApp::SubmitValid(const CommandOutcome& admitted, Error error,
                                     RequestKind kind, RequestTag tag, T Request::*field,
                                     const T& value) {
  if (admitted.result != CommandOutcomeCode::kAccepted) return admitted;
  if (error != Error::kOk) return Invalid(error);
  Request c;
  c.kind = kind;
  c.tag = tag;
  c.*field = value;
  return Submit(c);
}

CommandOutcome JointApp::Configure(const ControlConfig& config, RequestTag tag) {
  return SubmitValid(CheckStart(false), ControlTick::Validate(config),
                     RequestKind::kConfigure, tag, &Request::config, config);
}

CommandOutcome JointApp::SetCalibration(const Calibration& calibration, RequestTag tag) {
  return SubmitValid(CheckStart(false), Validate(calibration),
                     RequestKind::kSetCalibration, tag, &Request::calibration,
                     calibration);
}

CommandOutcome JointApp::StartTrial(const SineConfig& sine, RequestTag tag) {
  return SubmitValid(CheckStart(true), Validate(sine), RequestKind::kStartTrial, tag,
                     &Request::sine, sine);
}

CommandOutcome JointApp::StartCalibrationSweep(const RampedSineConfig& sweep,
                                               RequestTag tag) {
  return SubmitValid(CheckStart(false), Validate(sweep), RequestKind::kStartSweep, tag,
                     &Request::sweep, sweep);
}

CommandOutcome JointApp::StartStream(AngularVelocity max_rate, RequestTag tag) {
  return SubmitValid(CheckStart(true), ValidateStreamRate(max_rate, config().tick_hz),
                     RequestKind::kStartStream, tag, &Request::stream_rate, max_rate);
}

CommandOutcome JointApp::Stop(RequestTag tag) { return Submit(RequestKind::kStop, tag); }

CommandOutcome JointApp::ClearFaults(RequestTag tag) {
  return Submit(RequestKind::kClearFaults, tag);
}

void JointApp::ISR_FollowHost() {
  // A new fit of the attachment for the velocity estimator's model (SolveWindowFit).
  // Read in place: an empty queue costs two loads.
  if (const AttachmentParams* fit = attachments_.Front()) {
    (void)control_.SetAttachment(*fit);  // valid: SolveWindowFit checked it
    attachments_.DropFront();
  }
  // A plain load on the usual tick; the exclusive-access exchange only when a fault
  // is pending (a raise between the two is then taken with it, never lost).
  if (raised_fault_.load(std::memory_order_relaxed) != 0) {
    const auto raised =
        static_cast<Fault>(raised_fault_.exchange(0, std::memory_order_acquire));
    control_.RaiseExternalFault(raised);
  }
  if (control_.trajectory().mode() == TrajectoryMode::kStream) {
    (void)control_.trajectory().SetStreamTarget(
        Angle::FromRaw(stream_target_.load(std::memory_order_relaxed)));
  }
}

void JointApp::ISR_Done(RequestTag tag, CommandOutcome outcome) {
  AppEvent e;
  e.kind = AppEvent::Kind::kCommandDone;
  e.tick = result_.telemetry.tick;
  e.state = state_;
  e.tag = tag;
  e.outcome = outcome;
  events_.Push(e);
}

bool JointApp::PopWindowFit(std::uint32_t start_tick, InterfaceFitSums* out,
                            bool* of_trial) {
  WindowFitSums w;
  while (window_fits_.Pop(&w)) {
    if (w.start_tick == start_tick) {
      *out = w.sums;
      if (of_trial != nullptr) *of_trial = w.trial;
      return true;
    }
  }
  return false;
}

InterfaceFit JointApp::SolveWindowFit(std::uint32_t start_tick) {
  InterfaceFitSums sums;
  InterfaceFit fit;
  bool trial = false;
  if (!PopWindowFit(start_tick, &sums, &trial)) {
    fit.status = InterfaceFitStatus::kNotDelivered;
    return fit;
  }
  fit = SolveInterfaceFit(sums);
  if (trial && fit.valid()) {
    // A fit of a lossless or a stiff attachment can come out a little below zero (the
    // window's noise): the model takes it as zero.
    attachments_.Push(
        {std::max(fit.stiffness, Stiffness{}), std::max(fit.damping, Damping{})});
  }
  return fit;
}

JointApp::Snapshot JointApp::Latest() const {
  return done_.Read([this] {
    Snapshot s;
    s.telemetry = result_.telemetry;
    s.bridge_enabled = result_.actuation.bridge_enabled;
    s.state = state_;
    s.calibrated = calibrated_;
    return s;
  });
}

void JointApp::ISR_Enter(BoardState next) {
  if (next == state_) return;
  state_ = next;
  control_.Arm(next == BoardState::kRunning || next == BoardState::kCalibrating);
  AppEvent e;
  e.kind = AppEvent::Kind::kStateChanged;
  e.tick = result_.telemetry.tick;
  e.state = next;
  events_.Push(e);
}

void JointApp::ISR_ApplyRequest() {
  // Read in place: an empty mailbox costs two loads, a command no copy.
  const Request* c = requests_.Front();
  if (c == nullptr) return;
  if (c->kind == RequestKind::kClearFaults && state_ == BoardState::kFault) {
    // Judged in this tick's step, on this tick's sample; answered in ISR_AfterStep.
    control_.RequestClearFaults();
    clear_pending_ = true;
    clear_tag_ = c->tag;
  } else {
    ISR_Done(c->tag, ISR_Apply(*c));
  }
  requests_.DropFront();
}

CommandOutcome JointApp::ISR_Apply(const Request& c) {
  const bool idle = state_ == BoardState::kIdle;
  switch (c.kind) {
    case RequestKind::kConfigure:
    case RequestKind::kSetCalibration: {
      if (!idle) return {CommandOutcomeCode::kRefusedNotIdle, 0};
      const bool calibration = c.kind == RequestKind::kSetCalibration;
      // Validated when submitted; Configure checks again, so nothing unchecked runs.
      const ControlConfigError error = control_.Configure(
          calibration ? c.calibration.AppliedTo(control_.config()) : c.config);
      if (error != ControlConfigError::kOk) return Invalid(error);
      if (calibration) calibrated_ = true;
      config_generation_.store(config_generation_.load(std::memory_order_relaxed) + 1,
                               std::memory_order_release);
      return {};
    }
    case RequestKind::kStartTrial:
    case RequestKind::kStartSweep: {
      const bool trial = c.kind == RequestKind::kStartTrial;
      if (const CommandOutcome o = CheckStart(trial, state_, calibrated_);
          o.result != CommandOutcomeCode::kAccepted) {
        return o;
      }
      const TrajectoryError error = trial ? control_.trajectory().StartSine(c.sine)
                                          : control_.trajectory().StartSweep(c.sweep);
      if (error != TrajectoryError::kOk) return Invalid(error);
      ISR_Enter(trial ? BoardState::kRunning : BoardState::kCalibrating);
      windows_of_trial_ = trial;
      return {};
    }
    case RequestKind::kStartStream: {
      if (const CommandOutcome o = CheckStart(true, state_, calibrated_);
          o.result != CommandOutcomeCode::kAccepted) {
        return o;
      }
      // From where the motor is (idle, the bridge was off and it may have moved): no
      // jump on the first streamed tick; it holds there until targets arrive.
      const Angle from = result_.telemetry.motor;
      const TrajectoryError error =
          control_.trajectory().StartStream(from, c.stream_rate);
      if (error != TrajectoryError::kOk) return Invalid(error);
      stream_target_.store(from.raw(), std::memory_order_relaxed);
      ISR_Enter(BoardState::kRunning);
      return {};
    }
    case RequestKind::kStop:
      control_.trajectory().Stop();
      if (state_ != BoardState::kFault) ISR_Enter(BoardState::kIdle);
      return {};
    case RequestKind::kClearFaults:
      return {};  // no fault latched: nothing to clear
  }
  return {};
}

void JointApp::ISR_AfterStep() {
  if (clear_pending_) {
    clear_pending_ = false;
    const bool cleared =
        result_.clear == FaultClear::kCleared && result_.raised == Fault::kNone;
    if (cleared) ISR_Enter(BoardState::kIdle);
    ISR_Done(clear_tag_,
             cleared ? CommandOutcome{}
                     : CommandOutcome{CommandOutcomeCode::kRefusedFaultActive, 0});
  }
  if (result_.raised != Fault::kNone) {
    AppEvent e;
    e.kind = AppEvent::Kind::kFault;
    e.tick = result_.telemetry.tick;
    e.fault = result_.raised;
    events_.Push(e);
    ISR_Enter(BoardState::kFault);
  }
  if (result_.window_completed) {
    window_fits_.Push({result_.window.start_tick, windows_of_trial_, result_.window_fit});
    AppEvent e;
    e.kind = AppEvent::Kind::kWindow;
    e.tick = result_.telemetry.tick;
    e.state = state_;
    e.window = result_.window;
    events_.Push(e);
  }
  const bool moving =
      state_ == BoardState::kRunning || state_ == BoardState::kCalibrating;
  if (moving && result_.telemetry.segment == Segment::kIdle) ISR_Enter(BoardState::kIdle);
}

}  // namespace mjc::app
