#include "mjc/host/board_client.h"

#include <chrono>

namespace mjc::host {

using namespace mjc::protocol;

BoardClient::BoardClient(CanLink* link, std::uint8_t node) : link_(link), node_(node) {
  const IdFilter only_node{node, 0x00F};
  std::string why;
  link_->SetFilters({&only_node, 1}, &why);
}

std::optional<CommandOutcomeCode> BoardClient::Command(CommandCode code, int timeout_ms,
                                                       std::string* why) {
  const std::uint8_t seq = ++sequence_;
  last_result_.reset();
  if (!link_->Send(Encode(protocol::Command{code, seq}, node_), why)) return std::nullopt;
  const auto deadline =
      std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
  while (std::chrono::steady_clock::now() < deadline) {
    Poll(10);
    if (last_result_ && last_result_->sequence == seq && last_result_->code == code) {
      return last_result_->outcome;
    }
  }
  *why = "node " + std::to_string(node_) + " did not answer the command within " +
         std::to_string(timeout_ms) + " ms";
  return std::nullopt;
}

std::optional<std::int32_t> BoardClient::ReadParam(ParamId id, int timeout_ms,
                                                   std::string* why) {
  last_param_.reset();
  if (!link_->Send(Encode(ParamRead{id}, node_), why)) return std::nullopt;
  const auto deadline =
      std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
  while (std::chrono::steady_clock::now() < deadline) {
    Poll(10);
    if (last_param_ && last_param_->id == id) {
      if (last_param_->status != ParamStatus::kOk) {
        *why = "node " + std::to_string(node_) + " answered parameter " +
               std::to_string(static_cast<int>(id)) + " with status " +
               std::to_string(static_cast<int>(last_param_->status));
        return std::nullopt;
      }
      return last_param_->value;
    }
  }
  *why = "node " + std::to_string(node_) + " did not answer a parameter read within " +
         std::to_string(timeout_ms) + " ms";
  return std::nullopt;
}

bool BoardClient::SendTrialConfig(const TrialConfig& config, std::string* why) {
  return link_->Send(Encode(config, node_), why);
}

bool BoardClient::Poll(int timeout_ms) {
  bool any = false;
  for (auto r = link_->Receive(timeout_ms); r; r = link_->Receive(0)) {
    Handle(r->frame);
    any = true;
  }
  return any;
}

std::vector<BoardWindow> BoardClient::TakeWindows() {
  std::vector<BoardWindow> out;
  out.swap(windows_);
  return out;
}

void BoardClient::Handle(const CanFrame& f) {
  if (NodeOf(f.id) != node_) return;
  const auto ok = [this](DecodeError e) {
    if (e == DecodeError::kOk) return true;
    if (e != DecodeError::kWrongFunction) ++malformed_;
    return false;
  };
  switch (static_cast<Function>(FunctionOf(f.id))) {
    case Function::kCommandResult: {
      protocol::CommandResult r;
      if (ok(Decode(f, &r))) last_result_ = r;
      return;
    }
    case Function::kParamValue: {
      ParamValue v;
      if (ok(Decode(f, &v))) last_param_ = v;
      return;
    }
    case Function::kHeartbeat: {
      Heartbeat h;
      if (!ok(Decode(f, &h))) return;
      status_.heard = true;
      status_.state = h.state;
      status_.calibrated = h.calibrated;
      status_.bridge_enabled = h.bridge_enabled;
      status_.fault = h.fault;
      status_.tick = h.tick;
      return;
    }
    case Function::kFault: {
      FaultEvent e;
      if (ok(Decode(f, &e))) {
        status_.fault = e.fault;
        status_.state = BoardState::kFault;
      }
      return;
    }
    case Function::kTelemetryAngles: {
      TelemetryAngles a;
      if (ok(Decode(f, &a))) {
        status_.motor_rad = a.motor.ToDouble();
        status_.joint_rad = a.joint.ToDouble();
      }
      return;
    }
    case Function::kTelemetryTorque: {
      TelemetryTorque t;
      if (ok(Decode(f, &t))) status_.torque_Nm = t.torque.ToDouble();
      return;
    }
    case Function::kTelemetryPower: {
      TelemetryPower p;
      if (ok(Decode(f, &p))) status_.power_W = p.power.ToDouble();
      return;
    }
    case Function::kTelemetryEnergy: {
      TelemetryEnergy e;
      if (ok(Decode(f, &e))) status_.energy_J = e.energy.ToDouble();
      return;
    }
    // A window travels as five frames, header first and ticks last, sent back to back.
    case Function::kWindowHeader: {
      WindowHeader h;
      if (!ok(Decode(f, &h))) return;
      partial_ = BoardWindow{};
      partial_.motion = h.motion;
      partial_.repetition = h.repetition;
      partial_.eta_valid = h.eta_valid;
      partial_.eta_percent = h.eta_percent.ToDouble();
      return;
    }
    case Function::kWindowEnergy: {
      WindowEnergy e;
      if (!ok(Decode(f, &e))) return;
      partial_.loading_J = e.loading.ToDouble();
      partial_.unloading_J = e.unloading.ToDouble();
      return;
    }
    case Function::kWindowWork: {
      WindowWork w;
      if (!ok(Decode(f, &w))) return;
      partial_.positive_J = w.positive.ToDouble();
      partial_.negative_J = w.negative.ToDouble();
      return;
    }
    case Function::kWindowPeaks: {
      WindowPeaks p;
      if (!ok(Decode(f, &p))) return;
      partial_.peak_power_W = p.peak_power.ToDouble();
      partial_.peak_torque_Nm = p.peak_torque.ToDouble();
      return;
    }
    case Function::kWindowTicks: {
      WindowTicks t;
      if (!ok(Decode(f, &t))) return;
      partial_.start_tick = t.start_tick;
      partial_.peak_tick = t.start_tick + t.peak_offset;
      partial_.end_tick = t.start_tick + t.end_offset;
      windows_.push_back(partial_);
      return;
    }
    default:
      return;
  }
}

}  // namespace mjc::host
