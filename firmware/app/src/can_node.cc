#include "mjc/app/can_node.h"

#include <algorithm>

namespace mjc::app {
namespace {

using namespace mjc::protocol;

// mHz → Q15.16 Hz, rounded: exact integer arithmetic.
Frequency FromMilliHertz(std::uint16_t mhz) {
  return Frequency::FromRaw(
      static_cast<std::int32_t>((static_cast<std::int64_t>(mhz) * 65536 + 500) / 1000));
}

CommandOutcomeCode Wire(CommandResult r) { return static_cast<CommandOutcomeCode>(r); }
static_assert(static_cast<int>(CommandResult::kRefusedBusy) ==
              static_cast<int>(CommandOutcomeCode::kRefusedBusy));
static_assert(static_cast<int>(AppState::kFault) == static_cast<int>(BoardState::kFault));

}  // namespace

CanNode::CanNode(JointApp* app, const CanNodeConfig& config, CalibrationStore* store)
    : app_(app),
      config_(config),
      isotp_(MakeId(static_cast<std::uint8_t>(Function::kIsoTpFromBoard), config.node)),
      store_(store) {}

std::uint32_t CanNode::NowMs() const {
  return now_ / std::max<std::uint32_t>(1, app_->control().config().tick_hz / 1000);
}

void CanNode::ReplyCalibration(CalibrationResult result, std::uint8_t detail) {
  const std::uint8_t data[2] = {static_cast<std::uint8_t>(result), detail};
  const CanFrame reply = MakeSingleFrame(
      MakeId(static_cast<std::uint8_t>(Function::kIsoTpFromBoard), config_.node), data);
  if (!tx_.ISR_Push(reply)) ++counters_.tx_dropped;
}

void CanNode::HandleIsoTp(const CanFrame& frame) {
  CanFrame flow;
  const IsoTpEvent event = isotp_.Handle(frame, NowMs(), &flow);
  if (flow.length != 0 && !tx_.ISR_Push(flow)) ++counters_.tx_dropped;
  if (event == IsoTpEvent::kNone) return;
  if (event != IsoTpEvent::kComplete) {
    ++counters_.isotp_errors;
    if (event != IsoTpEvent::kMalformed) {
      ReplyCalibration(CalibrationResult::kReassemblyError,
                       static_cast<std::uint8_t>(event));
    }
    return;
  }
  CalibrationRecord record;
  std::uint8_t detail = 0;
  CalibrationResult result = DecodeCalibration(isotp_.payload(), &record, &detail);
  if (result == CalibrationResult::kAccepted) {
    const CommandOutcome o = app_->SetCalibration(record.backlash, record.sea_stiffness,
                                                  record.joint_zero_count);
    if (o.result == CommandResult::kRefusedNotIdle)
      result = CalibrationResult::kRefusedNotIdle;
    if (o.result == CommandResult::kRefusedInvalid) {
      result = CalibrationResult::kOutOfRange;
      detail = o.detail;
    }
    // Accepted while idle, so the bridge is off: keep it over a reset.
    if (result == CalibrationResult::kAccepted && store_ != nullptr &&
        store_->Save(record) != StoreResult::kOk) {
      ++counters_.storage_failures;
      result = CalibrationResult::kStorageFailed;
    }
  }
  if (result == CalibrationResult::kAccepted) {
    ++counters_.calibrations_accepted;
  } else {
    ++counters_.calibrations_refused;
  }
  ReplyCalibration(result, detail);
}

template <class M>
void CanNode::Send(const M& message) {
  if (!tx_.ISR_Push(Encode(message, config_.node))) ++counters_.tx_dropped;
}

void CanNode::Reply(CommandCode code, const CommandOutcome& outcome, std::uint8_t seq) {
  protocol::CommandResult r;
  r.code = code;
  r.outcome = Wire(outcome.result);
  r.detail = outcome.detail;
  r.sequence = seq;
  Send(r);
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
        last_setpoint_tick_ = app_->last().telemetry.tick;
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
      ++counters_.handled;
      HandleIsoTp(frame);
      return;
    case Function::kHostHeartbeat: {
      HostHeartbeat h;
      count(Decode(frame, &h));
      return;
    }
    default:
      ++counters_.ignored;  // a board-to-host message, or an unused function code
      return;
  }
}

void CanNode::HandleCommand(const Command& c) {
  last_command_ = c.code;
  last_sequence_ = c.sequence;
  const std::uint32_t hz = app_->control().config().tick_hz;
  CommandOutcome outcome;
  switch (c.code) {
    case CommandCode::kStop:
      streaming_ = false;
      outcome = app_->Stop();
      break;
    case CommandCode::kClearFaults:
      app_->SetCommandTimeout(false);  // the cause a stream timeout left behind
      outcome = app_->ClearFaults();
      break;
    case CommandCode::kStartTrial: {
      if (!have_trial_) {
        outcome = {CommandResult::kRefusedInvalid, 0};
        break;
      }
      SineConfig sine;
      sine.amplitude = trial_.amplitude;
      sine.frequency = FromMilliHertz(trial_.frequency_mHz);
      sine.repetitions = trial_.repetitions;
      sine.rest_ms = trial_.rest_100ms * 100u;
      sine.tick_rate_hz = hz;
      outcome = app_->StartTrial(sine);
      break;
    }
    case CommandCode::kStartSweep: {
      if (!have_sweep_) {
        outcome = {CommandResult::kRefusedInvalid, 0};
        break;
      }
      mjc::SweepConfig sweep;
      sweep.end_amplitude = sweep_.end_amplitude;
      sweep.frequency = FromMilliHertz(sweep_.frequency_mHz);
      sweep.repetitions = sweep_.repetitions;
      sweep.rest_ms = sweep_.rest_100ms * 100u;
      sweep.tick_rate_hz = hz;
      outcome = app_->StartCalibrationSweep(sweep);
      break;
    }
    case CommandCode::kStartStream:
      outcome = app_->StartStream(config_.stream_rate);
      if (outcome.result == CommandResult::kAccepted) {
        streaming_ = true;
        last_setpoint_tick_ = app_->last().telemetry.tick;
      }
      break;
  }
  Reply(c.code, outcome, c.sequence);
}

void CanNode::HandleParam(ParamId id, bool write, std::int32_t value) {
  ParamValue reply;
  reply.id = id;
  std::uint16_t* rate = nullptr;
  switch (id) {
    case ParamId::kTelemetryAnglesHz:
      rate = &config_.angles_hz;
      break;
    case ParamId::kTelemetryTorqueHz:
      rate = &config_.torque_hz;
      break;
    case ParamId::kTelemetryPowerHz:
      rate = &config_.power_hz;
      break;
    case ParamId::kTelemetryEnergyHz:
      rate = &config_.energy_hz;
      break;
    case ParamId::kTelemetryControlHz:
      rate = &config_.control_hz;
      break;
    case ParamId::kHeartbeatHz:
      rate = &config_.heartbeat_hz;
      break;
    case ParamId::kStreamTimeoutMs:
      rate = &config_.stream_timeout_ms;
      break;
    default:
      break;
  }
  if (rate != nullptr) {
    const std::int32_t limit =
        id == ParamId::kStreamTimeoutMs
            ? 60000
            : static_cast<std::int32_t>(app_->control().config().tick_hz);
    if (write && (value < 0 || value > limit)) {
      reply.status = ParamStatus::kOutOfRange;
    } else if (write) {
      *rate = static_cast<std::uint16_t>(value);
    }
    reply.value = *rate;
    return Send(reply);
  }
  // Control parameters: readable always, writable only while idle (a new ControlConfig
  // restarts the tick's state).
  ControlConfig config = app_->control().config();
  std::int32_t raw = 0;
  switch (id) {
    case ParamId::kPositionKp:
      raw = config.position.kp.raw();
      break;
    case ParamId::kPositionKi:
      raw = config.position.ki.raw();
      break;
    case ParamId::kPositionKd:
      raw = config.position.kd.raw();
      break;
    case ParamId::kPositionKff:
      raw = config.position.kff.raw();
      break;
    case ParamId::kVelocityWindow:
      raw = config.velocity_window;
      break;
    case ParamId::kTorqueMax:
      raw = config.supervisor.torque_max.raw();
      break;
    // The calibration in force: read-only (a calibration is uploaded whole over ISO-TP).
    case ParamId::kCalibrationRight:
    case ParamId::kCalibrationLeft:
    case ParamId::kCalibrationAlpha:
    case ParamId::kCalibrationStiffness:
    case ParamId::kCalibrationJointZero:
    case ParamId::kCalibrated:
      switch (id) {
        case ParamId::kCalibrationRight:
          reply.value = config.backlash.c_right.raw();
          break;
        case ParamId::kCalibrationLeft:
          reply.value = config.backlash.c_left.raw();
          break;
        case ParamId::kCalibrationAlpha:
          reply.value = config.backlash.alpha.raw();
          break;
        case ParamId::kCalibrationStiffness:
          reply.value = config.sea_stiffness.raw();
          break;
        case ParamId::kCalibrationJointZero:
          reply.value = config.joint_encoder.zero_offset;
          break;
        default:
          reply.value = app_->calibrated() ? 1 : 0;
          break;
      }
      if (write) reply.status = ParamStatus::kReadOnly;
      return Send(reply);
    default:
      reply.status = ParamStatus::kUnknown;
      return Send(reply);
  }
  reply.value = raw;
  if (write) {
    if (app_->state() != AppState::kIdle) {
      reply.status = ParamStatus::kRefusedNotIdle;
      return Send(reply);
    }
    switch (id) {
      case ParamId::kPositionKp:
        config.position.kp = decltype(config.position.kp)::FromRaw(value);
        break;
      case ParamId::kPositionKi:
        config.position.ki = decltype(config.position.ki)::FromRaw(value);
        break;
      case ParamId::kPositionKd:
        config.position.kd = decltype(config.position.kd)::FromRaw(value);
        break;
      case ParamId::kPositionKff:
        config.position.kff = decltype(config.position.kff)::FromRaw(value);
        break;
      case ParamId::kVelocityWindow:
        if (value < 0 || value > 0xFFFF) {
          reply.status = ParamStatus::kOutOfRange;
          return Send(reply);
        }
        config.velocity_window = static_cast<std::uint16_t>(value);
        break;
      case ParamId::kTorqueMax:
        config.supervisor.torque_max = Torque::FromRaw(value);
        break;
      default:
        break;
    }
    // Validate here so the reply can say so; the app re-validates in the tick.
    if (ControlTick::Validate(config) != ControlConfigError::kOk) {
      reply.status = ParamStatus::kOutOfRange;
      return Send(reply);
    }
    const CommandOutcome o = app_->Configure(config);
    reply.status = o.result == CommandResult::kAccepted ? ParamStatus::kOk
                                                        : ParamStatus::kRefusedNotIdle;
    if (reply.status == ParamStatus::kOk) reply.value = value;
  }
  Send(reply);
}

void CanNode::SendEvent(const AppEvent& e) {
  switch (e.kind) {
    case AppEvent::Kind::kFault: {
      FaultEvent f;
      f.fault = e.fault;
      f.tick = e.tick;
      f.state = BoardState::kFault;
      Send(f);
      streaming_ = false;
      return;
    }
    case AppEvent::Kind::kCommandRefused:
      // Refused in the tick (the state changed after the main loop accepted it).
      Reply(last_command_, e.refusal, last_sequence_);
      return;
    case AppEvent::Kind::kStateChanged:
      if (e.state != AppState::kRunning) streaming_ = false;
      next_heartbeat_ = 0;  // tell the host at once
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
      WindowTicks t;
      t.start_tick = w.start_tick;
      t.peak_offset = static_cast<std::uint16_t>(w.peak_tick - w.start_tick);
      t.end_offset = static_cast<std::uint16_t>(w.end_tick - w.start_tick);
      Send(t);
      return;
    }
  }
}

bool CanNode::Due(std::uint16_t hz, std::uint32_t* next_tick) {
  if (hz == 0) return false;
  if (static_cast<std::int32_t>(now_ - *next_tick) < 0) return false;
  const std::uint32_t period = app_->control().config().tick_hz / hz;
  *next_tick = now_ + (period == 0 ? 1u : period);
  return true;
}

void CanNode::Poll() {
  const TickResult& r = app_->last();
  now_ = r.telemetry.tick;
  AppEvent e;
  while (app_->PopEvent(&e)) SendEvent(e);
  if (isotp_.Poll(NowMs()) == IsoTpEvent::kTimeout) {
    ++counters_.isotp_errors;
    ReplyCalibration(CalibrationResult::kReassemblyError,
                     static_cast<std::uint8_t>(IsoTpEvent::kTimeout));
  }

  if (streaming_) {
    const std::uint32_t timeout_ticks =
        config_.stream_timeout_ms * (app_->control().config().tick_hz / 1000u);
    if (now_ - last_setpoint_tick_ > timeout_ticks) {
      app_->SetCommandTimeout(true);  // the next tick latches kCommandTimeout
      ++counters_.stream_timeouts;
      streaming_ = false;
    }
  }

  const Telemetry& t = r.telemetry;
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
                          static_cast<BoardState>(app_->state())});
  }
  if (Due(config_.heartbeat_hz, &next_heartbeat_)) {
    Heartbeat h;
    h.state = static_cast<BoardState>(app_->state());
    h.calibrated = app_->calibrated();
    h.bridge_enabled = r.actuation.bridge_enabled;
    h.fault = t.fault;
    h.tick = now_;
    Send(h);
  }
}

}  // namespace mjc::app
