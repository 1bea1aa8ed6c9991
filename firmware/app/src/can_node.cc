// The CAN node's dispatch: frames to their handlers, commands to the app, host
// supervision, and the main loop's poll. Parameters, calibration uploads and reports
// (events and telemetry as frames) have files of their own.
#include "mjc/app/can_node.h"

#include <limits>

namespace mjc::app {
namespace {

using protocol::CanFrame;
using protocol::CommandCode;
using protocol::DecodeError;
using protocol::Function;

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

// A window is half a cycle, 2·Q ticks; WindowTicks reports it in 16-bit offsets. A
// frequency the trajectory would refuse anyway is left for it to refuse.
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

// The host reads the board's clock off the heartbeat's tick at this rate.
static_assert(ControlConfig{}.tick_hz == protocol::kBoardTickHz);

}  // namespace

CanNode::CanNode(JointApp* app, const CanNodeConfig& config, CalibrationStore* store)
    : app_(app),
      config_(config),
      isotp_(protocol::MakeId(static_cast<std::uint8_t>(Function::kIsoTpFromBoard),
                              config.node)),
      store_(store) {}

CanNodeCounters CanNode::counters() const {
  CanNodeCounters c = counters_;
  c.tx_dropped = tx_.dropped();
  c.events_dropped = app_->dropped_events();
  return c;
}

void CanNode::Push(const CanFrame& frame) { (void)tx_.Push(frame); }  // drops counted

void CanNode::HandleFrame(const CanFrame& frame) {
  const auto count = [this](DecodeError e) {
    if (e == DecodeError::kOk) {
      ++counters_.handled;
      return true;
    }
    ++counters_.malformed[static_cast<std::size_t>(e)];
    return false;
  };
  // Every node's, ahead of the node filter: the emergency stop.
  if (frame.id == protocol::IdOf<protocol::StopAll>(protocol::kEveryNode)) {
    protocol::StopAll s;
    DecodeError e = Decode(frame, &s);
    // Another protocol's frame on identifier 0 (a wrong key) is no stop.
    if (e == DecodeError::kOk && s.key != protocol::kStopAllKey) {
      e = DecodeError::kFieldOutOfRange;
    }
    if (!count(e)) return;
    // The next tick latches it and disables the bridge (the path of every fault).
    app_->RaiseFault(Fault::kEmergencyStop);
    ++counters_.emergency_stops;
    return;
  }
  if (frame.id > 0x7FFu || protocol::NodeOf(frame.id) != config_.node) {
    ++counters_.ignored;
    return;
  }
  switch (static_cast<Function>(protocol::FunctionOf(frame.id))) {
    case Function::kCommand: {
      protocol::Command c;
      if (count(Decode(frame, &c))) HandleCommand(c);
      return;
    }
    case Function::kTrialConfig:
      have_trial_ = count(Decode(frame, &trial_)) || have_trial_;
      return;
    case Function::kSweepConfig:
      have_sweep_ = count(Decode(frame, &sweep_)) || have_sweep_;
      return;
    case Function::kSetpoint: {
      protocol::Setpoint s;
      if (count(Decode(frame, &s))) {
        app_->SetStreamTarget(s.position);
        last_setpoint_tick_ = clock_.ticks();
      }
      return;
    }
    case Function::kParamRead: {
      protocol::ParamRead r;
      if (count(Decode(frame, &r))) HandleParam(r.id, false, 0);
      return;
    }
    case Function::kParamWrite: {
      protocol::ParamWrite w;
      if (count(Decode(frame, &w))) HandleParam(w.id, true, w.value);
      return;
    }
    case Function::kIsoTpToBoard:
      HandleIsoTp(frame);
      return;
    case Function::kBootHold: {
      if (!config_.bootloader) {
        ++counters_.ignored;
        return;
      }
      protocol::BootHold h;
      if (count(Decode(frame, &h))) HandleBootHold(h);
      return;
    }
    case Function::kStopAll: {  // addressed to one node: no broadcast, refused
      protocol::StopAll s;
      (void)count(Decode(frame, &s));
      return;
    }
    case Function::kHostHeartbeat: {
      protocol::HostHeartbeat h;
      // Only the heartbeat of the session that started the motion keeps it going.
      if (count(Decode(frame, &h)) && h.session != 0 && h.session == motion_session_) {
        last_host_tick_ = clock_.ticks();
      }
      return;
    }
    default:
      ++counters_.ignored;  // a board-to-host message, or an unused function code
      return;
  }
}

void CanNode::HandleCommand(const protocol::Command& c) {
  const RequestTag tag =
      Tag(Origin::kCommand,
          (std::uint32_t{static_cast<std::uint8_t>(c.code)} << 8) | c.sequence) |
      (RequestTag{c.session} << 32);
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
    // Only with the configuration the command names: a configuration frame from
    // another sender since (or a changed one) is not what this session asked for.
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
      o = app_->StartStream(config_.stream_rate, tag);
      break;
  }
  // Accepted: answered with the tick's verdict (SendEvent).
  if (o.result != CommandOutcomeCode::kAccepted) return Answer(tag, o);
  if (start) {
    start_pending_ = true;
    start_session_ = c.session;
    start_code_ = c.code;
    start_config_ = config;
  }
}

void CanNode::Answer(RequestTag tag, const CommandOutcome& outcome) {
  switch (OriginOf(tag)) {
    case Origin::kCommand: {
      protocol::CommandResult r;
      r.code = static_cast<CommandCode>((tag >> 8) & 0xFFu);
      r.outcome = outcome.result;
      r.detail = outcome.detail;
      r.sequence = static_cast<std::uint8_t>(tag & 0xFFu);
      r.session = SessionOf(tag);
      // Who holds the board: the start awaiting its verdict, or the motion running.
      r.owner = start_pending_ ? start_session_ : motion_session_;
      const bool held = outcome.result == CommandOutcomeCode::kRefusedNotIdle ||
                        outcome.result == CommandOutcomeCode::kRefusedBusy;
      if (IsStart(r.code) && held) {
        r.detail = start_pending_ ? static_cast<std::uint8_t>(start_code_) : motion_code_;
      }
      return Send(r);
    }
    case Origin::kParam:
      return SendParam(static_cast<protocol::ParamId>(tag & 0xFFFFu),
                       outcome.result == CommandOutcomeCode::kAccepted
                           ? protocol::ParamStatus::kOk
                       : outcome.result == CommandOutcomeCode::kRefusedInvalid
                           ? protocol::ParamStatus::kOutOfRange
                       : outcome.result == CommandOutcomeCode::kRefusedBusy
                           ? protocol::ParamStatus::kRefusedBusy
                           : protocol::ParamStatus::kRefusedNotIdle);
    case Origin::kCalibration:
      return AnswerCalibration(outcome);
  }
}

void CanNode::OnVerdict(const AppEvent& e) {
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
  // The motion's first frame: what it runs, under the name its session gave it.
  if (started) {
    Send(protocol::MotionConfig{static_cast<CommandCode>(motion_code_), motion_session_,
                                motion_config_});
  }
}

void CanNode::HandleBootHold(const protocol::BootHold& hold) {
  protocol::BootResult r;
  r.request = protocol::BootRequest::kHold;
  if (hold.key != protocol::kBootHoldKey) {
    r.error = protocol::BootError::kBadRequest;
    return Send(r);
  }
  // Only at rest: no motion running or about to start (a reset stops the bridge, but a
  // motion is the host's to stop, and a host that asks mid-trial has made a mistake it
  // should hear about). A fault leaves the bridge off: a faulted board may be updated.
  const JointApp::Snapshot last = app_->Latest();
  const bool moving = last.state == BoardState::kRunning ||
                      last.state == BoardState::kCalibrating || last.bridge_enabled ||
                      start_pending_;
  if (moving) {
    ++counters_.boot_holds_refused;
    r.error = protocol::BootError::kMotionRunning;
    return Send(r);
  }
  leaving_ = true;
  Send(r);  // {hold, none}: the bootloader's BootStatus follows within milliseconds
}

void CanNode::OnBusOff() {
  ++counters_.bus_off;
  app_->RaiseFault(Fault::kCanBusOff);
}

void CanNode::Supervise(const JointApp::Snapshot& last) {
  // Streamed setpoints that stopped coming.
  const bool streaming =
      last.state == BoardState::kRunning && last.telemetry.segment == Segment::kStream;
  if (streaming && clock_.ticks() - last_setpoint_tick_ >
                       BoardClock::TicksFromMs(config_.stream_timeout_ms, tick_hz())) {
    app_->RaiseFault(Fault::kCommandTimeout);  // the next tick latches it
    ++counters_.stream_timeouts;
    last_setpoint_tick_ = clock_.ticks();  // once: the fault ends the stream
  }
  // A motion whose commanding session went quiet.
  const bool host_quiet = motion_session_ != 0 && config_.host_timeout_ms != 0 &&
                          clock_.ticks() - last_host_tick_ >
                              BoardClock::TicksFromMs(config_.host_timeout_ms, tick_hz());
  if (host_quiet) {
    motion_session_ = 0;  // once: the fault ends the motion
    app_->RaiseFault(Fault::kHostHeartbeatLost);
    ++counters_.host_timeouts;
  }
}

void CanNode::Poll() {
  // One tick's values throughout: the tick may interrupt this poll at any point.
  const JointApp::Snapshot last = app_->Latest();
  clock_.Advance(last.telemetry.tick, tick_hz());
  AppEvent e;
  while (app_->PopEvent(&e)) SendEvent(e);
  AnnounceWindow(last);
  PollUpload();
  Supervise(last);
  SendTelemetry(last);
}

}  // namespace mjc::app
