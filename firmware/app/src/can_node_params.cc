// Parameters over the bus: reads of any, writes of the node's own (applied at once) and
// of the control configuration's (applied by the tick while idle); what each may take
// is the protocol's list (protocol/params.h), where each lives is param_access.
#include "mjc/app/can_node.h"
#include "mjc/app/param_access.h"

namespace mjc::app {

using protocol::ParamAccess;
using protocol::ParamId;
using protocol::ParamStatus;

void CanNode::SendParam(ParamId id, ParamStatus status) {
  protocol::ParamValue reply;
  reply.id = id;
  reply.status = status;
  ControlConfig control = service_->control();
  bool calibrated = service_->Latest().calibrated;
  (void)ReadParam(id, {&config_, &control, &calibrated}, &reply.value);
  Send(reply);
}

void CanNode::RefuseParam(ParamId id, ParamStatus status, std::int32_t bound) {
  protocol::ParamValue reply;
  reply.id = id;
  reply.status = status;
  reply.value = bound;
  Send(reply);
}

void CanNode::HandleParam(ParamId id, bool write, std::int32_t value) {
  // The decoder refused ids the list does not have.
  const protocol::ParamInfo& info = *protocol::FindParam(id);
  if (!write) return SendParam(id, ParamStatus::kOk);
  if (info.access == ParamAccess::kReadOnly) return SendParam(id, ParamStatus::kReadOnly);
  // The list's range: what keeps each protection on, the image's ceiling above.
  if (value < info.min_raw) {
    return RefuseParam(id, ParamStatus::kBelowMinimum,
                       static_cast<std::int32_t>(info.min_raw));
  }
  if (value > info.max_raw) {
    return RefuseParam(id, ParamStatus::kAboveMaximum,
                       static_cast<std::int32_t>(info.max_raw));
  }
  // What protects stays as it is while a motion runs: the motion started under it.
  if (protocol::RefusedWhileMoving(info.access) && service_->MotionRuns()) {
    return SendParam(id, ParamStatus::kRefusedNotIdle);
  }
  ControlConfig control = service_->control();
  CanNodeConfig node = config_;
  bool calibrated = false;
  const ParamFields fields{&node, &control, &calibrated};
  std::int32_t bound = 0;
  if (BeyondJointLimit(id, value, fields, &bound)) {
    return RefuseParam(id, ParamStatus::kBeyondJointLimit, bound);
  }
  if (info.access == ParamAccess::kNode || info.access == ParamAccess::kGuard) {
    (void)WriteParam(id, value, fields);
    config_ = node;
    TellSupervision();
    return SendParam(id, ParamStatus::kOk);
  }
  // The control configuration (and the joint's limits, some of which live in it):
  // applied by the tick, which judges it whole and answers.
  if (service_->ConfigChangePending()) return SendParam(id, ParamStatus::kRefusedBusy);
  (void)WriteParam(id, value, fields);
  KeepWithinJointLimits(fields);
  if (id == ParamId::kJointTorqueLimit &&
      control.supervisor.torque_max == service_->control().supervisor.torque_max) {
    config_ = node;  // torque_max already within: nothing for the tick to apply
    return SendParam(id, ParamStatus::kOk);
  }
  // Answered by the service's report (kParamDone): a refusal at once, or the tick's
  // verdict. A tightened joint torque limit holds from now on (the tick applies
  // torque_max), unless the configuration was refused at once.
  service_->Configure(control, id);
  if (service_->ConfigChangePending()) config_ = node;
}

}  // namespace mjc::app
