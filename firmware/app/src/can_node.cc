// The CAN node's dispatch: frames decoded into the service's requests, and the main
// loop's poll. Parameters, calibration uploads and reports (the service's reports and
// telemetry as frames) have files of their own.
#include "mjc/app/can_node.h"

#include <utility>

namespace mjc::app {
namespace {

using protocol::CanFrame;
using protocol::CommandCode;
using protocol::DecodeError;
using protocol::Function;

}  // namespace

CanNode::CanNode(service::JointService* service, const CanNodeConfig& config)
    : service_(service),
      config_(config),
      isotp_(protocol::MakeId(static_cast<std::uint8_t>(Function::kIsoTpFromBoard),
                              config.node)) {
  service_->Attach(this);
  TellSupervision();
}

void CanNode::TellSupervision() {
  service_->SetSupervision(
      {config_.stream_timeout_ms, config_.host_timeout_ms, config_.stream_rate});
}

CanNodeCounters CanNode::counters() const {
  CanNodeCounters c = counters_;
  c.tx_dropped = tx_.dropped();
  c.events_dropped = service_->dropped_events();
  c.stream_timeouts = service_->counters().stream_timeouts;
  c.host_timeouts = service_->counters().host_timeouts;
  c.storage_failures = service_->counters().storage_failures;
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
    service_->EmergencyStop();
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
      if (count(Decode(frame, &c))) {
        service_->Submit({c.code, c.sequence, c.session, c.config});
      }
      return;
    }
    case Function::kTrialConfig: {
      protocol::TrialConfig t;
      if (count(Decode(frame, &t))) service_->SetTrialConfig(t);
      return;
    }
    case Function::kSweepConfig: {
      protocol::SweepConfig w;
      if (count(Decode(frame, &w))) service_->SetSweepConfig(w);
      return;
    }
    case Function::kSetpoint: {
      protocol::Setpoint s;
      if (count(Decode(frame, &s))) service_->Setpoint(s.position);
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
      if (!count(Decode(frame, &h))) return;
      if (h.key != protocol::kBootHoldKey) {
        protocol::BootResult r;
        r.request = protocol::BootRequest::kHold;
        r.error = protocol::BootError::kBadRequest;
        return Send(r);
      }
      service_->BootHold();  // answered by its report
      return;
    }
    case Function::kStopAll: {  // addressed to one node: no broadcast, refused
      protocol::StopAll s;
      (void)count(Decode(frame, &s));
      return;
    }
    case Function::kHostHeartbeat: {
      protocol::HostHeartbeat h;
      if (count(Decode(frame, &h))) service_->HostHeartbeat(h.session);
      return;
    }
    default:
      ++counters_.ignored;  // a board-to-host message, or an unused function code
      return;
  }
}

void CanNode::OnBusOff() {
  ++counters_.bus_off;
  service_->BusOff();
}

void CanNode::Poll() {
  PollUpload();
  SendTelemetry(service_->last());
}

}  // namespace mjc::app
