#include "mjc/app/param_access.h"

#include "mjc/app/can_node.h"

namespace mjc::app {
namespace {

using protocol::ParamId;

// The protocol this image speaks: a constant, bound like a field.
constexpr std::uint16_t kImageProtocol = protocol::kVersion;

// Calls visit(field) with the field bound to `id`; false for an unbound id. The one
// place that names each parameter's field.
template <class Visit>
constexpr bool VisitParam(ParamId id, CanNodeConfig& node, ControlConfig& control,
                          bool& calibrated, Visit&& visit) {
  switch (id) {
    case ParamId::kTelemetryAnglesHz:
      visit(node.rates.angles_hz);
      return true;
    case ParamId::kTelemetryTorqueHz:
      visit(node.rates.torque_hz);
      return true;
    case ParamId::kTelemetryPowerHz:
      visit(node.rates.power_hz);
      return true;
    case ParamId::kTelemetryEnergyHz:
      visit(node.rates.energy_hz);
      return true;
    case ParamId::kTelemetryControlHz:
      visit(node.rates.control_hz);
      return true;
    case ParamId::kHeartbeatHz:
      visit(node.rates.heartbeat_hz);
      return true;
    case ParamId::kStreamTimeoutMs:
      visit(node.stream_timeout_ms);
      return true;
    case ParamId::kHostTimeoutMs:
      visit(node.host_timeout_ms);
      return true;
    case ParamId::kPositionKp:
      visit(control.position.kp);
      return true;
    case ParamId::kPositionKi:
      visit(control.position.ki);
      return true;
    case ParamId::kPositionKd:
      visit(control.position.kd);
      return true;
    case ParamId::kPositionKff:
      visit(control.position.kff);
      return true;
    case ParamId::kVelocityWindow:
      visit(control.velocity_window);
      return true;
    case ParamId::kAttachmentPriorStiffness:
      visit(control.attachment_prior.stiffness);
      return true;
    case ParamId::kAttachmentPriorDamping:
      visit(control.attachment_prior.damping);
      return true;
    case ParamId::kTorqueMax:
      visit(control.supervisor.torque_max);
      return true;
    case ParamId::kJointTorqueLimit:
      visit(node.joint_torque_limit);
      return true;
    case ParamId::kJointAngleMin:
      visit(control.supervisor.joint_min);
      return true;
    case ParamId::kJointAngleMax:
      visit(control.supervisor.joint_max);
      return true;
    case ParamId::kVelocityMax:
      visit(control.supervisor.velocity_max);
      return true;
    case ParamId::kCalibrationRight:
      visit(control.backlash.c_right);
      return true;
    case ParamId::kCalibrationLeft:
      visit(control.backlash.c_left);
      return true;
    case ParamId::kCalibrationAlpha:
      visit(control.backlash.alpha);
      return true;
    case ParamId::kCalibrationStiffness:
      visit(control.sea_stiffness);
      return true;
    case ParamId::kCalibrationJointZero:
      visit(control.joint_encoder.zero_offset);
      return true;
    case ParamId::kCalibrationFriction:
      visit(control.backlash.cable_friction);
      return true;
    case ParamId::kCalibrated:
      visit(calibrated);
      return true;
    case ParamId::kBuildId:
      visit(node.identity.build);
      return true;
    case ParamId::kProtocolVersion:
      visit(kImageProtocol);
      return true;
  }
  return false;
}

// Every id of the protocol's list has a field.
consteval bool EveryParamIsBound() {
  for (const protocol::ParamInfo& p : protocol::kParams) {
    CanNodeConfig node;
    ControlConfig control;
    bool calibrated = false;
    if (!VisitParam(p.id, node, control, calibrated, [](const auto&) {})) return false;
  }
  return true;
}
static_assert(EveryParamIsBound(), "a parameter of protocol/params.h has no field");

template <class F>
std::int32_t RawOf(const F& field) {
  return field.raw();
}
std::int32_t RawOf(std::uint16_t field) { return field; }
std::int32_t RawOf(bool field) { return field ? 1 : 0; }
// The build id travels as the same 32 bits, read as signed.
std::int32_t RawOf(std::uint32_t field) { return static_cast<std::int32_t>(field); }

template <class F>
bool SetRaw(F* field, std::int32_t raw) {
  *field = F::FromRaw(raw);
  return true;
}
bool SetRaw(std::uint16_t* field, std::int32_t raw) {
  *field = static_cast<std::uint16_t>(raw);  // the list's range fits 16 bits
  return true;
}
bool SetRaw(bool*, std::int32_t) { return false; }
bool SetRaw(const std::uint16_t*, std::int32_t) { return false; }
bool SetRaw(std::uint32_t*, std::int32_t) { return false; }

}  // namespace

bool ReadParam(ParamId id, const ParamFields& f, std::int32_t* raw) {
  return VisitParam(id, *f.node, *f.control, *f.calibrated,
                    [&](const auto& field) { *raw = RawOf(field); });
}

bool WriteParam(ParamId id, std::int32_t raw, const ParamFields& f) {
  bool written = false;
  VisitParam(id, *f.node, *f.control, *f.calibrated,
             [&](auto& field) { written = SetRaw(&field, raw); });
  return written;
}

bool BeyondJointLimit(ParamId id, std::int32_t raw, const ParamFields& f,
                      std::int32_t* bound) {
  const SupervisorConfig& s = f.control->supervisor;
  switch (id) {
    case ParamId::kTorqueMax:
    case ParamId::kJointTorqueLimit:
      *bound = f.node->joint_torque_limit.raw();
      return raw > *bound;
    case ParamId::kJointAngleMin:
      *bound = s.joint_min.raw();
      return raw < *bound;
    case ParamId::kJointAngleMax:
      *bound = s.joint_max.raw();
      return raw > *bound;
    default:
      return false;
  }
}

void KeepWithinJointLimits(const ParamFields& f) {
  Torque& torque = f.control->supervisor.torque_max;
  if (torque > f.node->joint_torque_limit) torque = f.node->joint_torque_limit;
}

}  // namespace mjc::app
