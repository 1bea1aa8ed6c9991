// What the board reports: the service's reports (command verdicts, faults, state
// changes, window summaries and fits, window starts) as frames, and telemetry, its
// heartbeat and its BoardInfo at their cadences.
#include "mjc/app/can_node.h"

namespace mjc::app {

using protocol::WireEnergy;

void CanNode::DoTake(const service::Report& r) {
  using Kind = service::Report::Kind;
  switch (r.kind) {
    case Kind::kCommandDone:
      return Send(r.command);
    case Kind::kMotionStarted:
      return Send(r.motion);
    case Kind::kParamDone: {
      const CommandOutcomeCode o = r.outcome.result;
      return SendParam(r.param, o == CommandOutcomeCode::kAccepted
                                    ? protocol::ParamStatus::kOk
                                : o == CommandOutcomeCode::kRefusedInvalid
                                    ? protocol::ParamStatus::kOutOfRange
                                : o == CommandOutcomeCode::kRefusedBusy
                                    ? protocol::ParamStatus::kRefusedBusy
                                    : protocol::ParamStatus::kRefusedNotIdle);
    }
    case Kind::kCalibrationDone:
      return ReplyCalibration(r.calibration, r.detail);
    case Kind::kBootHold: {
      if (r.boot != protocol::BootError::kNone) ++counters_.boot_holds_refused;
      protocol::BootResult b;
      b.request = protocol::BootRequest::kHold;
      b.error = r.boot;
      // Accepted ({hold, none}): the bootloader's BootStatus follows within milliseconds.
      return Send(b);
    }
    case Kind::kFault: {
      protocol::FaultEvent f;
      f.fault = r.fault;
      f.tick = r.tick;
      f.state = protocol::BoardState::kFault;
      return Send(f);
    }
    case Kind::kStateChanged:
      heartbeat_.Now(service_->clock().ticks());  // tell the host at once
      return;
    case Kind::kWindow:
      return SendWindow(r.window, r.fit);
    case Kind::kWindowStart:
      return Send(r.window_start);
  }
}

void CanNode::SendWindow(const WindowSummary& w, const InterfaceFit& fit) {
  protocol::WindowHeader h;
  h.motion = w.motion;
  h.repetition = w.repetition;
  h.eta_valid = w.eta_valid;
  h.eta_percent = w.eta_percent;
  h.fit_status = fit.status;
  Send(h);
  Send(protocol::WindowEnergy{FixedCast<WireEnergy>(w.loading),
                              FixedCast<WireEnergy>(w.unloading)});
  Send(protocol::WindowWork{FixedCast<WireEnergy>(w.positive_work),
                            FixedCast<WireEnergy>(w.negative_work)});
  Send(protocol::WindowPeaks{w.peak_power, w.peak_torque});
  // Fits: trials and sweeps with longer windows are refused (kDetailWindowTooLong).
  protocol::WindowTicks t;
  t.start_tick = w.start_tick;
  t.peak_offset = static_cast<std::uint16_t>(w.peak_tick - w.start_tick);
  t.end_offset = static_cast<std::uint16_t>(w.end_tick - w.start_tick);
  Send(t);
  Send(protocol::WindowFit{fit.stiffness, fit.damping});
  Send(protocol::WindowFitResidual{fit.offset, fit.residual_rms});
}

void CanNode::SendTelemetry(const JointApp::Snapshot& last) {
  const Telemetry& t = last.telemetry;
  const std::uint32_t now = service_->clock().ticks();
  const std::uint32_t hz = tick_hz();
  if (angles_.Due(now, config_.rates.angles_hz, hz)) SendAngles(t);
  if (torque_.Due(now, config_.rates.torque_hz, hz)) {
    Send(protocol::TelemetryTorque{t.torque, t.cable_side});
  }
  if (power_.Due(now, config_.rates.power_hz, hz)) {
    Send(protocol::TelemetryPower{t.power, t.joint_velocity});
  }
  if (energy_.Due(now, config_.rates.energy_hz, hz)) {
    Send(protocol::TelemetryEnergy{EnergyScale(hz).ToEnergy(t.energy_sum)});
  }
  if (control_.Due(now, config_.rates.control_hz, hz)) {
    Send(protocol::TelemetryControl{t.setpoint, t.duty, t.segment, last.state});
  }
  if (info_.Due(now, config_.rates.info_hz, hz)) Send(config_.identity);
  if (heartbeat_.Due(now, config_.rates.heartbeat_hz, hz)) {
    protocol::Heartbeat h;
    h.state = last.state;
    h.calibrated = last.calibrated;
    h.bridge_enabled = last.bridge_enabled;
    h.fault = t.fault;
    h.tick = now;
    Send(h);
  }
}

void CanNode::SendAngles(const Telemetry& t) {
  if (!config_.fd) return Send(protocol::TelemetryAngles{t.motor, t.joint});
  batch_.motor[batch_fill_] = t.motor;
  batch_.joint[batch_fill_] = t.joint;
  if (++batch_fill_ < protocol::TelemetryAngleBatch::kSamples) return;
  // A batch the transmit queue drops still advances the count: the host sees the gap.
  Send(batch_);
  batch_.first_sample += protocol::TelemetryAngleBatch::kSamples;
  batch_fill_ = 0;
}

}  // namespace mjc::app
