// The joint board's main loop around its application (see joint_service.h): requests
// to the app, the tick's verdicts and events to reports, the window fits back to the
// tick, the calibration's store, and the host's supervision.
#include "mjc/service/joint_service.h"

#include <limits>

namespace mjc::service {
namespace {

using app::AppEvent;
using app::BoardClock;
using protocol::CalibrationResult;
using protocol::CommandCode;

// mHz → Q15.16 Hz, rounded: exact integer arithmetic.
Frequency FromMilliHertz(std::uint16_t mhz) {
  return Frequency::FromRaw(
      static_cast<std::int32_t>((static_cast<std::int64_t>(mhz) * 65536 + 500) / 1000));
}

// The amplitude a wire trial or sweep config carries, into the core's config.
void SetAmplitude(const protocol::TrialConfig& wire, SineConfig* c) {
  c->amplitude = wire.amplitude;
}
void SetAmplitude(const protocol::SweepConfig& wire, RampedSineConfig* c) {
  c->end_amplitude = wire.end_amplitude;
}

// A wire trial or sweep config, into the core's config.
template <class Core, class Wire>
Core Oscillation(const Wire& wire, std::uint32_t tick_hz) {
  Core c;
  c.frequency = FromMilliHertz(wire.frequency_mHz);
  c.repetitions = wire.repetitions;
  c.rest_ms = wire.rest_100ms * 100u;
  c.tick_rate_hz = tick_hz;
  SetAmplitude(wire, &c);
  return c;
}

// A window is half a cycle, 2·Q ticks; a window's report gives its end and peak in
// 16-bit offsets. A frequency the trajectory would refuse anyway is left for it to
// refuse.
bool WindowReportable(Frequency f, std::uint32_t tick_hz) {
  if (f <= Frequency{} || 4u * static_cast<std::uint64_t>(f.raw()) >
                              (std::uint64_t{tick_hz} << Frequency::kFracBits)) {
    return true;
  }
  return 2u * std::uint64_t{QuarterTicks(f, tick_hz)} <=
         std::numeric_limits<std::uint16_t>::max();
}

// Starts a trial or a sweep (`start` takes the core's config) from the wire config the
// host sent: refused without one, or when a window would be too long to report.
template <class Core, class Wire, class Start>
CommandOutcome StartOscillation(bool have, const Wire& wire, std::uint32_t tick_hz,
                                Start start) {
  if (!have) return {CommandOutcomeCode::kRefusedInvalid, 0};
  const Core c = Oscillation<Core>(wire, tick_hz);
  if (!WindowReportable(c.frequency, tick_hz)) {
    return {CommandOutcomeCode::kRefusedInvalid, protocol::kDetailWindowTooLong};
  }
  return start(c);
}

bool IsStart(CommandCode code) {
  return code == CommandCode::kStartTrial || code == CommandCode::kStartSweep ||
         code == CommandCode::kStartStream;
}

CalibrationResult CalibrationResultOf(CommandOutcomeCode r) {
  switch (r) {
    case CommandOutcomeCode::kAccepted:
      return CalibrationResult::kAccepted;
    case CommandOutcomeCode::kRefusedInvalid:
      return CalibrationResult::kOutOfRange;
    case CommandOutcomeCode::kRefusedBusy:
      return CalibrationResult::kRefusedBusy;
    default:
      return CalibrationResult::kRefusedNotIdle;
  }
}

// The host reads the board's clock off the heartbeat's tick at this rate.
static_assert(ControlConfig{}.tick_hz == protocol::kBoardTickHz);

}  // namespace

JointService::JointService(app::JointApp* app, app::CalibrationStore* store)
    : app_(app), store_(store) {}

std::optional<app::CalibrationStore::Loaded> JointService::Boot() {
  if (store_ == nullptr) return std::nullopt;
  return app::RestoreCalibration(*app_, *store_);
}

std::uint8_t JointService::unreadable_pages() const {
  return store_ == nullptr ? 0 : store_->unreadable_pages();
}

void JointService::Submit(const CommandRequest& c) {
  const app::RequestTag tag =
      Tag(Origin::kCommand,
          (std::uint32_t{static_cast<std::uint8_t>(c.code)} << 8) | c.sequence) |
      (app::RequestTag{c.session} << 32);
  const std::uint32_t hz = tick_hz();
  const bool start = IsStart(c.code);
  // One start at a time in the mailbox, so that the session its verdict binds the
  // motion to is known without doubt; none once the board is leaving for its bootloader.
  if (start && (start_pending_ || leaving_)) {
    return Answer(tag, {CommandOutcomeCode::kRefusedBusy, 0});
  }
  CommandOutcome o;
  protocol::ConfigDigest config = 0;  // of the motion a start would run (0: a stream)
  switch (c.code) {
    case CommandCode::kStop:
      o = app_->Stop(tag);
      break;
    case CommandCode::kClearFaults:
      o = app_->ClearFaults(tag);
      break;
    // Only with the configuration the command names: a configuration from another
    // sender since (or a changed one) is not what this session asked for.
    case CommandCode::kStartTrial:
      config = protocol::ConfigDigestOf(trial_);
      if (have_trial_ && c.config != config) {
        o = {CommandOutcomeCode::kRefusedInvalid, protocol::kDetailConfigMismatch};
        break;
      }
      o = StartOscillation<SineConfig>(have_trial_, trial_, hz, [&](const SineConfig& s) {
        return app_->StartTrial(s, tag);
      });
      break;
    case CommandCode::kStartSweep:
      config = protocol::ConfigDigestOf(sweep_);
      if (have_sweep_ && c.config != config) {
        o = {CommandOutcomeCode::kRefusedInvalid, protocol::kDetailConfigMismatch};
        break;
      }
      o = StartOscillation<RampedSineConfig>(
          have_sweep_, sweep_, hz,
          [&](const RampedSineConfig& s) { return app_->StartCalibrationSweep(s, tag); });
      break;
    case CommandCode::kStartStream:
      o = app_->StartStream(supervision_.stream_rate, tag);
      break;
  }
  // Accepted: answered with the tick's verdict (OnVerdict).
  if (o.result != CommandOutcomeCode::kAccepted) return Answer(tag, o);
  if (start) {
    start_pending_ = true;
    start_session_ = c.session;
    start_code_ = c.code;
    start_config_ = config;
  }
}

void JointService::SetTrialConfig(const protocol::TrialConfig& trial) {
  trial_ = trial;
  have_trial_ = true;
}

void JointService::SetSweepConfig(const protocol::SweepConfig& sweep) {
  sweep_ = sweep;
  have_sweep_ = true;
}

void JointService::Setpoint(Angle target) {
  app_->SetStreamTarget(target);
  last_setpoint_tick_ = clock_.ticks();
}

void JointService::HostHeartbeat(protocol::SessionId session) {
  // Only the heartbeat of the session that started the motion keeps it going.
  if (session != 0 && session == motion_session_) last_host_tick_ = clock_.ticks();
}

void JointService::BootHold() {
  Report r;
  r.kind = Report::Kind::kBootHold;
  // Only at rest: no motion running or about to start (a reset stops the bridge, but a
  // motion is the host's to stop, and a host that asks mid-trial has made a mistake it
  // should hear about). A fault leaves the bridge off: a faulted board may be updated.
  if (MotionRuns()) {
    r.boot = protocol::BootError::kMotionRunning;
    return Emit(r);
  }
  leaving_ = true;
  Emit(r);
}

void JointService::Upload(const protocol::CalibrationRecord& record) {
  if (config_change_pending_ || leaving_) {
    Report r;
    r.kind = Report::Kind::kCalibrationDone;
    r.calibration = CalibrationResult::kRefusedBusy;
    return Emit(r);
  }
  const CommandOutcome o = app_->SetCalibration(
      {record.backlash, record.sea_stiffness, record.joint_zero_count},
      Tag(Origin::kCalibration, 0));
  if (o.result != CommandOutcomeCode::kAccepted) return AnswerCalibration(o);
  pending_record_ = record;
  config_change_pending_ = true;
}

void JointService::Configure(const ControlConfig& control, protocol::ParamId id) {
  const app::RequestTag tag = Tag(Origin::kParam, static_cast<std::uint16_t>(id));
  const CommandOutcome o = app_->Configure(control, tag);
  if (o.result != CommandOutcomeCode::kAccepted) return Answer(tag, o);
  config_change_pending_ = true;
}

bool JointService::MotionRuns() const {
  const app::JointApp::Snapshot last = app_->Latest();
  return last.state == BoardState::kRunning || last.state == BoardState::kCalibrating ||
         last.bridge_enabled || start_pending_;
}

void JointService::Answer(app::RequestTag tag, const CommandOutcome& outcome) {
  Report r;
  switch (OriginOf(tag)) {
    case Origin::kCommand: {
      r.kind = Report::Kind::kCommandDone;
      protocol::CommandResult& c = r.command;
      c.code = static_cast<CommandCode>((tag >> 8) & 0xFFu);
      c.outcome = outcome.result;
      c.detail = outcome.detail;
      c.sequence = static_cast<std::uint8_t>(tag & 0xFFu);
      c.session = SessionOf(tag);
      // Who holds the board: the start awaiting its verdict, or the motion running.
      c.owner = start_pending_ ? start_session_ : motion_session_;
      const bool held = outcome.result == CommandOutcomeCode::kRefusedNotIdle ||
                        outcome.result == CommandOutcomeCode::kRefusedBusy;
      if (IsStart(c.code) && held) {
        c.detail = start_pending_ ? static_cast<std::uint8_t>(start_code_) : motion_code_;
      }
      return Emit(r);
    }
    case Origin::kParam:
      r.kind = Report::Kind::kParamDone;
      r.param = static_cast<protocol::ParamId>(tag & 0xFFFFu);
      r.outcome = outcome;
      return Emit(r);
    case Origin::kCalibration:
      return AnswerCalibration(outcome);
  }
}

void JointService::AnswerCalibration(const CommandOutcome& o) {
  Report r;
  r.kind = Report::Kind::kCalibrationDone;
  r.calibration = CalibrationResultOf(o.result);
  r.detail = o.detail;
  // Applied while idle, so the bridge is off: keep it over a reset.
  if (r.calibration == CalibrationResult::kAccepted && store_ != nullptr &&
      store_->Save(pending_record_) != app::StoreResult::kOk) {
    ++counters_.storage_failures;
    r.calibration = CalibrationResult::kStorageFailed;
  }
  Emit(r);
}

void JointService::OnVerdict(const AppEvent& e) {
  bool started = false;
  switch (OriginOf(e.tag)) {
    case Origin::kCommand: {
      const auto code = static_cast<CommandCode>((e.tag >> 8) & 0xFFu);
      if (!IsStart(code)) break;
      start_pending_ = false;
      if (e.outcome.result == CommandOutcomeCode::kAccepted) {
        // The motion is its commander's: supervised by its heartbeats from now on.
        motion_session_ = start_session_;
        motion_code_ = static_cast<std::uint8_t>(code);
        motion_config_ = start_config_;
        last_host_tick_ = e.tick;
        if (code == CommandCode::kStartStream) last_setpoint_tick_ = e.tick;
        started = true;
      }
      break;
    }
    case Origin::kParam:
    case Origin::kCalibration:
      config_change_pending_ = false;
      break;
  }
  Answer(e.tag, e.outcome);
  // The motion's first report: what it runs, under the name its session gave it.
  if (started) {
    Report r;
    r.kind = Report::Kind::kMotionStarted;
    r.motion = {static_cast<CommandCode>(motion_code_), motion_session_, motion_config_};
    Emit(r);
  }
}

void JointService::OnEvent(const AppEvent& e) {
  Report r;
  switch (e.kind) {
    case AppEvent::Kind::kFault:
      r.kind = Report::Kind::kFault;
      r.fault = e.fault;
      r.tick = e.tick;
      return Emit(r);
    case AppEvent::Kind::kCommandDone:
      return OnVerdict(e);
    case AppEvent::Kind::kStateChanged:
      // A motion that ended is nobody's any more.
      if (e.state == BoardState::kIdle || e.state == BoardState::kFault) {
        motion_session_ = 0;
        motion_code_ = 0;
      }
      r.kind = Report::Kind::kStateChanged;
      r.state = e.state;
      return Emit(r);
    case AppEvent::Kind::kWindow:
      r.kind = Report::Kind::kWindow;
      r.window = e.window;
      // The attachment's fit, solved here from the tick's sums; a trial's valid fit
      // becomes the tick's attachment model (JointApp::SolveWindowFit).
      r.fit = app_->SolveWindowFit(e.window.start_tick);
      return Emit(r);
  }
}

void JointService::AnnounceWindow() {
  const Segment segment = last_.telemetry.segment;
  if (segment != last_segment_ &&
      (segment == Segment::kFlexionLoading || segment == Segment::kExtensionLoading)) {
    Report r;
    r.kind = Report::Kind::kWindowStart;
    r.window_start.motion =
        segment == Segment::kFlexionLoading ? Motion::kFlexion : Motion::kExtension;
    r.window_start.start_tick = last_.telemetry.tick;
    r.window_start.config16 = static_cast<std::uint16_t>(motion_config_ & 0xFFFFu);
    Emit(r);
  }
  last_segment_ = segment;
}

void JointService::Supervise() {
  const std::uint32_t hz = tick_hz();
  // Streamed setpoints that stopped coming.
  const bool streaming =
      last_.state == BoardState::kRunning && last_.telemetry.segment == Segment::kStream;
  if (streaming && clock_.ticks() - last_setpoint_tick_ >
                       BoardClock::TicksFromMs(supervision_.stream_timeout_ms, hz)) {
    app_->RaiseFault(Fault::kCommandTimeout);  // the next tick latches it
    ++counters_.stream_timeouts;
    last_setpoint_tick_ = clock_.ticks();  // once: the fault ends the stream
  }
  // A motion whose commanding session went quiet.
  const bool host_quiet = motion_session_ != 0 && supervision_.host_timeout_ms != 0 &&
                          clock_.ticks() - last_host_tick_ >
                              BoardClock::TicksFromMs(supervision_.host_timeout_ms, hz);
  if (host_quiet) {
    motion_session_ = 0;  // once: the fault ends the motion
    app_->RaiseFault(Fault::kHostHeartbeatLost);
    ++counters_.host_timeouts;
  }
}

void JointService::Poll() {
  // One tick's values throughout: the tick may interrupt this poll at any point.
  last_ = app_->Latest();
  clock_.Advance(last_.telemetry.tick, tick_hz());
  AppEvent e;
  while (app_->PopEvent(&e)) OnEvent(e);
  AnnounceWindow();
  Supervise();
}

}  // namespace mjc::service
