#include "mjc/app/can_node.h"

#include <limits>

namespace mjc::app {
namespace {

using namespace mjc::protocol;

// mHz → Q15.16 Hz, rounded: exact integer arithmetic.
Frequency FromMilliHertz(std::uint16_t mhz) {
  return Frequency::FromRaw(
      static_cast<std::int32_t>((static_cast<std::int64_t>(mhz) * 65536 + 500) / 1000));
}

// The timing a wire trial or sweep config carries, into the core's config.
template <class Core, class Wire>
Core Oscillation(const Wire& wire, std::uint32_t tick_hz) {
  Core c;
  c.frequency = FromMilliHertz(wire.frequency_mHz);
  c.repetitions = wire.repetitions;
  c.rest_ms = wire.rest_100ms * 100u;
  c.tick_rate_hz = tick_hz;
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

// At least `ms` (rounded up) in ticks.
std::uint32_t TicksFromMs(std::uint32_t ms, std::uint32_t tick_hz) {
  return static_cast<std::uint32_t>((std::uint64_t{ms} * tick_hz + 999u) / 1000u);
}

// Request tags: the origin in the top byte; a command's code and sequence, or a
// parameter's id, below.
RequestTag Tag(std::uint8_t origin, std::uint32_t low) {
  return (std::uint32_t{origin} << 24) | low;
}

ParamStatus ParamStatusOf(CommandResult r) {
  switch (r) {
    case CommandResult::kAccepted:
      return ParamStatus::kOk;
    case CommandResult::kRefusedInvalid:
      return ParamStatus::kOutOfRange;
    case CommandResult::kRefusedBusy:
      return ParamStatus::kRefusedBusy;
    default:
      return ParamStatus::kRefusedNotIdle;
  }
}

CalibrationResult CalibrationResultOf(CommandResult r) {
  switch (r) {
    case CommandResult::kAccepted:
      return CalibrationResult::kAccepted;
    case CommandResult::kRefusedInvalid:
      return CalibrationResult::kOutOfRange;
    case CommandResult::kRefusedBusy:
      return CalibrationResult::kRefusedBusy;
    default:
      return CalibrationResult::kRefusedNotIdle;
  }
}

// The ControlConfig field behind a writable control parameter, as visit(field); false
// for any other id. Fixed-point fields travel as their raw integers.
template <class Config, class Visit>
bool VisitControlParam(ParamId id, Config& c, Visit&& visit) {
  switch (id) {
    case ParamId::kPositionKp:
      visit(c.position.kp);
      return true;
    case ParamId::kPositionKi:
      visit(c.position.ki);
      return true;
    case ParamId::kPositionKd:
      visit(c.position.kd);
      return true;
    case ParamId::kPositionKff:
      visit(c.position.kff);
      return true;
    case ParamId::kVelocityWindow:
      visit(c.velocity_window);
      return true;
    case ParamId::kTorqueMax:
      visit(c.supervisor.torque_max);
      return true;
    default:
      return false;
  }
}

template <class F>
std::int32_t RawOf(const F& field) {
  return field.raw();
}
std::int32_t RawOf(std::uint16_t field) { return field; }

template <class F>
bool SetRaw(F* field, std::int32_t value) {
  *field = F::FromRaw(value);
  return true;
}
bool SetRaw(std::uint16_t* field, std::int32_t value) {
  if (value < 0 || value > std::numeric_limits<std::uint16_t>::max()) return false;
  *field = static_cast<std::uint16_t>(value);
  return true;
}

// The calibration in force, read-only over the bus.
bool ReadCalibrationParam(ParamId id, const ControlConfig& c, bool calibrated,
                          std::int32_t* value) {
  switch (id) {
    case ParamId::kCalibrationRight:
      *value = c.backlash.c_right.raw();
      return true;
    case ParamId::kCalibrationLeft:
      *value = c.backlash.c_left.raw();
      return true;
    case ParamId::kCalibrationAlpha:
      *value = c.backlash.alpha.raw();
      return true;
    case ParamId::kCalibrationStiffness:
      *value = c.sea_stiffness.raw();
      return true;
    case ParamId::kCalibrationJointZero:
      *value = c.joint_encoder.zero_offset;
      return true;
    case ParamId::kCalibrated:
      *value = calibrated ? 1 : 0;
      return true;
    default:
      return false;
  }
}

CommandOutcomeCode Wire(CommandResult r) { return static_cast<CommandOutcomeCode>(r); }
static_assert(static_cast<int>(CommandResult::kRefusedBusy) ==
              static_cast<int>(CommandOutcomeCode::kRefusedBusy));
static_assert(static_cast<int>(AppState::kFault) == static_cast<int>(BoardState::kFault));
// The host reads the board's clock off the heartbeat's tick at this rate.
static_assert(ControlConfig{}.tick_hz == kBoardTickHz);

}  // namespace

CanNode::CanNode(JointApp* app, const CanNodeConfig& config, CalibrationStore* store)
    : app_(app),
      config_(config),
      isotp_(MakeId(static_cast<std::uint8_t>(Function::kIsoTpFromBoard), config.node)),
      store_(store) {}

CanNodeCounters CanNode::counters() const {
  CanNodeCounters c = counters_;
  c.tx_dropped = tx_.dropped();
  c.events_dropped = app_->dropped_events();
  return c;
}

void CanNode::Push(const CanFrame& frame) { (void)tx_.Push(frame); }  // drops counted

template <class M>
void CanNode::Send(const M& message) {
  Push(Encode(message, config_.node));
}

void CanNode::ReplyCalibration(CalibrationResult result, std::uint8_t detail) {
  if (result == CalibrationResult::kAccepted) {
    ++counters_.calibrations_accepted;
  } else {
    ++counters_.calibrations_refused;
  }
  const std::uint8_t data[2] = {static_cast<std::uint8_t>(result), detail};
  Push(MakeSingleFrame(
      MakeId(static_cast<std::uint8_t>(Function::kIsoTpFromBoard), config_.node), data));
}

void CanNode::HandleIsoTp(const CanFrame& frame) {
  CanFrame flow;
  const IsoTpEvent event = isotp_.Handle(frame, now_ms_, &flow);
  if (event == IsoTpEvent::kMalformed) {
    ++counters_.isotp_malformed;
    return;
  }
  ++counters_.handled;
  if (flow.length != 0) Push(flow);
  if (event == IsoTpEvent::kNone) return;
  if (event != IsoTpEvent::kComplete) {
    ++counters_.isotp_errors;
    return ReplyCalibration(CalibrationResult::kReassemblyError,
                            static_cast<std::uint8_t>(event));
  }
  CalibrationRecord record;
  std::uint8_t detail = 0;
  const CalibrationResult decoded = DecodeCalibration(isotp_.payload(), &record, &detail);
  if (decoded != CalibrationResult::kAccepted) return ReplyCalibration(decoded, detail);
  if (config_change_pending_) return ReplyCalibration(CalibrationResult::kRefusedBusy, 0);
  const CommandOutcome o = app_->SetCalibration(
      {record.backlash, record.sea_stiffness, record.joint_zero_count},
      Tag(static_cast<std::uint8_t>(Origin::kCalibration), 0));
  if (o.result != CommandResult::kAccepted) return AnswerCalibration(o);
  pending_record_ = record;
  config_change_pending_ = true;
}

void CanNode::AnswerCalibration(const CommandOutcome& o) {
  CalibrationResult result = CalibrationResultOf(o.result);
  // Applied while idle, so the bridge is off: keep it over a reset.
  if (result == CalibrationResult::kAccepted && store_ != nullptr &&
      store_->Save(pending_record_) != StoreResult::kOk) {
    ++counters_.storage_failures;
    result = CalibrationResult::kStorageFailed;
  }
  ReplyCalibration(result, o.detail);
}

void CanNode::HandleFrame(const CanFrame& frame) {
  if (frame.id > 0x7FFu || NodeOf(frame.id) != config_.node) {
    ++counters_.ignored;
    return;
  }
  const auto count = [this](DecodeError e) {
    if (e == DecodeError::kOk) {
      ++counters_.handled;
      return true;
    }
    ++counters_.malformed[static_cast<std::size_t>(e)];
    return false;
  };
  switch (static_cast<Function>(FunctionOf(frame.id))) {
    case Function::kCommand: {
      Command c;
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
        last_setpoint_tick_ = now_;
      }
      return;
    }
    case Function::kParamRead: {
      ParamRead r;
      if (count(Decode(frame, &r))) HandleParam(r.id, false, 0);
      return;
    }
    case Function::kParamWrite: {
      ParamWrite w;
      if (count(Decode(frame, &w))) HandleParam(w.id, true, w.value);
      return;
    }
    case Function::kIsoTpToBoard:
      HandleIsoTp(frame);
      return;
    case Function::kHostHeartbeat: {
      HostHeartbeat h;
      // Only the heartbeat of the session that started the motion keeps it going.
      if (count(Decode(frame, &h)) && h.session != 0 && h.session == motion_session_) {
        last_host_tick_ = now_;
      }
      return;
    }
    default:
      ++counters_.ignored;  // a board-to-host message, or an unused function code
      return;
  }
}

void CanNode::HandleCommand(const Command& c) {
  const RequestTag tag =
      Tag(static_cast<std::uint8_t>(Origin::kCommand),
          (std::uint32_t{static_cast<std::uint8_t>(c.code)} << 8) | c.sequence);
  const std::uint32_t hz = app_->control().config().tick_hz;
  const bool start = c.code == CommandCode::kStartTrial ||
                     c.code == CommandCode::kStartSweep ||
                     c.code == CommandCode::kStartStream;
  // One start at a time in the mailbox, so that the session its verdict binds the
  // motion to is known without doubt.
  if (start && start_pending_) return Answer(tag, {CommandResult::kRefusedBusy, 0});
  CommandOutcome o;
  switch (c.code) {
    case CommandCode::kStop:
      o = app_->Stop(tag);
      break;
    case CommandCode::kClearFaults:
      o = app_->ClearFaults(tag);
      break;
    case CommandCode::kStartTrial: {
      if (!have_trial_) {
        o = {CommandResult::kRefusedInvalid, 0};
        break;
      }
      auto sine = Oscillation<SineConfig>(trial_, hz);
      sine.amplitude = trial_.amplitude;
      o = WindowReportable(sine.frequency, hz)
              ? app_->StartTrial(sine, tag)
              : CommandOutcome{CommandResult::kRefusedInvalid, kDetailWindowTooLong};
      break;
    }
    case CommandCode::kStartSweep: {
      if (!have_sweep_) {
        o = {CommandResult::kRefusedInvalid, 0};
        break;
      }
      auto sweep = Oscillation<mjc::SweepConfig>(sweep_, hz);
      sweep.end_amplitude = sweep_.end_amplitude;
      o = WindowReportable(sweep.frequency, hz)
              ? app_->StartCalibrationSweep(sweep, tag)
              : CommandOutcome{CommandResult::kRefusedInvalid, kDetailWindowTooLong};
      break;
    }
    case CommandCode::kStartStream:
      o = app_->StartStream(config_.stream_rate, tag);
      break;
  }
  // Accepted: answered with the tick's verdict (SendEvent).
  if (o.result != CommandResult::kAccepted) return Answer(tag, o);
  if (start) {
    start_pending_ = true;
    start_session_ = c.session;
  }
}

void CanNode::SendParam(ParamId id, ParamStatus status) {
  ParamValue reply;
  reply.id = id;
  reply.status = status;
  const ControlConfig& config = app_->control().config();
  if (!VisitControlParam(id, config,
                         [&](const auto& field) { reply.value = RawOf(field); })) {
    (void)ReadCalibrationParam(id, config, app_->calibrated(), &reply.value);
  }
  Send(reply);
}

void CanNode::HandleParam(ParamId id, bool write, std::int32_t value) {
  // The node's own: transmit rates (at most the tick rate) and the stream timeout.
  std::uint16_t* own = nullptr;
  std::int32_t low = 0;
  std::int32_t high = static_cast<std::int32_t>(app_->control().config().tick_hz);
  switch (id) {
    case ParamId::kTelemetryAnglesHz:
      own = &config_.angles_hz;
      break;
    case ParamId::kTelemetryTorqueHz:
      own = &config_.torque_hz;
      break;
    case ParamId::kTelemetryPowerHz:
      own = &config_.power_hz;
      break;
    case ParamId::kTelemetryEnergyHz:
      own = &config_.energy_hz;
      break;
    case ParamId::kTelemetryControlHz:
      own = &config_.control_hz;
      break;
    case ParamId::kHeartbeatHz:
      own = &config_.heartbeat_hz;
      break;
    case ParamId::kStreamTimeoutMs:
      own = &config_.stream_timeout_ms;
      low = 1;
      high = 60000;
      break;
    case ParamId::kHostTimeoutMs:
      own = &config_.host_timeout_ms;
      high = 60000;
      break;
    default:
      break;
  }
  if (id == ParamId::kBuildId) {
    ParamValue reply;
    reply.id = id;
    reply.status = write ? ParamStatus::kReadOnly : ParamStatus::kOk;
    reply.value = static_cast<std::int32_t>(config_.identity.build);
    return Send(reply);
  }
  if (own != nullptr) {
    ParamValue reply;
    reply.id = id;
    if (write && (value < low || value > high)) {
      reply.status = ParamStatus::kOutOfRange;
    } else if (write) {
      *own = static_cast<std::uint16_t>(value);
    }
    reply.value = *own;
    return Send(reply);
  }

  // The control config's: readable always; written through the app, which applies it
  // in the tick while idle. The calibration's: read-only (uploaded whole over ISO-TP).
  ControlConfig config = app_->control().config();
  bool in_range = true;
  const bool control = VisitControlParam(
      id, config, [&](auto& field) { in_range = SetRaw(&field, value); });
  std::int32_t ignored = 0;
  if (!control) {
    const bool calibration = ReadCalibrationParam(id, config, false, &ignored);
    if (!calibration) return SendParam(id, ParamStatus::kUnknown);
    return SendParam(id, write ? ParamStatus::kReadOnly : ParamStatus::kOk);
  }
  if (!write) return SendParam(id, ParamStatus::kOk);
  if (!in_range) return SendParam(id, ParamStatus::kOutOfRange);
  if (config_change_pending_) return SendParam(id, ParamStatus::kRefusedBusy);
  const RequestTag tag =
      Tag(static_cast<std::uint8_t>(Origin::kParam), static_cast<std::uint16_t>(id));
  const CommandOutcome o = app_->Configure(config, tag);
  if (o.result != CommandResult::kAccepted) return Answer(tag, o);
  config_change_pending_ = true;
}

void CanNode::Answer(RequestTag tag, const CommandOutcome& outcome) {
  switch (static_cast<Origin>(tag >> 24)) {
    case Origin::kCommand: {
      protocol::CommandResult r;
      r.code = static_cast<CommandCode>((tag >> 8) & 0xFFu);
      r.outcome = Wire(outcome.result);
      r.detail = outcome.detail;
      r.sequence = static_cast<std::uint8_t>(tag & 0xFFu);
      return Send(r);
    }
    case Origin::kParam:
      return SendParam(static_cast<ParamId>(tag & 0xFFFFu),
                       ParamStatusOf(outcome.result));
    case Origin::kCalibration:
      return AnswerCalibration(outcome);
  }
}

void CanNode::SendEvent(const AppEvent& e) {
  switch (e.kind) {
    case AppEvent::Kind::kFault: {
      FaultEvent f;
      f.fault = e.fault;
      f.tick = e.tick;
      f.state = BoardState::kFault;
      return Send(f);
    }
    case AppEvent::Kind::kCommandDone: {
      const auto origin = static_cast<Origin>(e.tag >> 24);
      if (origin == Origin::kParam || origin == Origin::kCalibration) {
        config_change_pending_ = false;
      }
      const auto code = static_cast<CommandCode>((e.tag >> 8) & 0xFFu);
      const bool start =
          origin == Origin::kCommand &&
          (code == CommandCode::kStartTrial || code == CommandCode::kStartSweep ||
           code == CommandCode::kStartStream);
      if (start) {
        start_pending_ = false;
        if (e.outcome.result == CommandResult::kAccepted) {
          // The motion is its commander's: supervised by its heartbeats from now on.
          motion_session_ = start_session_;
          last_host_tick_ = e.tick;
          if (code == CommandCode::kStartStream) last_setpoint_tick_ = e.tick;
        }
      }
      return Answer(e.tag, e.outcome);
    }
    case AppEvent::Kind::kStateChanged:
      // A motion that ended is nobody's any more.
      if (e.state == AppState::kIdle || e.state == AppState::kFault) motion_session_ = 0;
      next_heartbeat_ = now_;  // tell the host at once
      return;
    case AppEvent::Kind::kWindow: {
      const WindowSummary& w = e.window;
      WindowHeader h;
      h.motion = w.motion;
      h.repetition = w.repetition;
      h.eta_valid = w.eta_valid;
      h.eta_percent = w.eta_percent;
      Send(h);
      Send(WindowEnergy{FixedCast<WireEnergy>(w.loading),
                        FixedCast<WireEnergy>(w.unloading)});
      Send(WindowWork{FixedCast<WireEnergy>(w.positive_work),
                      FixedCast<WireEnergy>(w.negative_work)});
      Send(WindowPeaks{w.peak_power, w.peak_torque});
      // Fits: trials and sweeps with longer windows are refused (kDetailWindowTooLong).
      WindowTicks t;
      t.start_tick = w.start_tick;
      t.peak_offset = static_cast<std::uint16_t>(w.peak_tick - w.start_tick);
      t.end_offset = static_cast<std::uint16_t>(w.end_tick - w.start_tick);
      return Send(t);
    }
  }
}

void CanNode::AdvanceClock(std::uint32_t tick) {
  // Whole milliseconds carried with their remainder: exact at any tick rate, and the
  // millisecond clock wraps on its own, not when the tick counter does.
  const std::uint32_t hz = app_->control().config().tick_hz;
  const std::uint64_t scaled = std::uint64_t{tick - now_} * 1000u + ms_remainder_;
  now_ms_ += static_cast<std::uint32_t>(scaled / hz);
  ms_remainder_ = static_cast<std::uint32_t>(scaled % hz);
  now_ = tick;
}

bool CanNode::Due(std::uint16_t hz, std::uint32_t* next_tick) {
  if (hz == 0) return false;
  if (static_cast<std::int32_t>(now_ - *next_tick) < 0) return false;
  const std::uint32_t period = app_->control().config().tick_hz / hz;
  *next_tick = now_ + (period == 0 ? 1u : period);
  return true;
}

void CanNode::OnBusOff() {
  ++counters_.bus_off;
  app_->RaiseFault(Fault::kCanBusOff);
}

void CanNode::Poll() {
  // One tick's values throughout: the tick may interrupt this poll at any point.
  const JointApp::Snapshot last = app_->Latest();
  const Telemetry& t = last.telemetry;
  AdvanceClock(t.tick);
  AppEvent e;
  while (app_->PopEvent(&e)) SendEvent(e);
  if (isotp_.Poll(now_ms_) == IsoTpEvent::kTimeout) {
    ++counters_.isotp_errors;
    ReplyCalibration(CalibrationResult::kReassemblyError,
                     static_cast<std::uint8_t>(IsoTpEvent::kTimeout));
  }

  const bool streaming =
      last.state == AppState::kRunning && t.segment == Segment::kStream;
  if (streaming &&
      now_ - last_setpoint_tick_ >
          TicksFromMs(config_.stream_timeout_ms, app_->control().config().tick_hz)) {
    app_->RaiseFault(Fault::kCommandTimeout);  // the next tick latches it
    ++counters_.stream_timeouts;
    last_setpoint_tick_ = now_;  // once: the fault ends the stream
  }
  // Host supervision: a motion whose commanding session went quiet stops.
  const bool host_quiet =
      motion_session_ != 0 && config_.host_timeout_ms != 0 &&
      now_ - last_host_tick_ >
          TicksFromMs(config_.host_timeout_ms, app_->control().config().tick_hz);
  if (host_quiet) {
    motion_session_ = 0;  // once: the fault ends the motion
    app_->RaiseFault(Fault::kHostHeartbeatLost);
    ++counters_.host_timeouts;
  }

  if (Due(config_.angles_hz, &next_angles_)) Send(TelemetryAngles{t.motor, t.joint});
  if (Due(config_.torque_hz, &next_torque_))
    Send(TelemetryTorque{t.torque, t.cable_side});
  if (Due(config_.power_hz, &next_power_))
    Send(TelemetryPower{t.power, t.joint_velocity});
  if (Due(config_.energy_hz, &next_energy_)) {
    Send(TelemetryEnergy{app_->control().energy_scale().ToEnergy(t.energy_sum)});
  }
  if (Due(config_.control_hz, &next_control_)) {
    Send(TelemetryControl{t.setpoint, t.duty, t.segment,
                          static_cast<BoardState>(last.state)});
  }
  if (Due(config_.info_hz, &next_info_)) Send(config_.identity);
  if (Due(config_.heartbeat_hz, &next_heartbeat_)) {
    Heartbeat h;
    h.state = static_cast<BoardState>(last.state);
    h.calibrated = last.calibrated;
    h.bridge_enabled = last.bridge_enabled;
    h.fault = t.fault;
    h.tick = now_;
    Send(h);
  }
}

}  // namespace mjc::app
