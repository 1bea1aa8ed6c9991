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
  ControlConfig control = app_->config();
  bool calibrated = app_->Latest().calibrated;
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

bool CanNode::MotionRuns() const {
  const JointApp::Snapshot last = app_->Latest();
  return last.state == BoardState::kRunning || last.state == BoardState::kCalibrating ||
         last.bridge_enabled || start_pending_;
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
  if (protocol::RefusedWhileMoving(info.access) && MotionRuns()) {
    return SendParam(id, ParamStatus::kRefusedNotIdle);
  }
  ControlConfig control = app_->config();
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
    return SendParam(id, ParamStatus::kOk);
  }
  // The control configuration (and the joint's limits, some of which live in it):
  // applied by the tick, which judges it whole and answers.
  if (config_change_pending_) return SendParam(id, ParamStatus::kRefusedBusy);
  (void)WriteParam(id, value, fields);
  KeepWithinJointLimits(fields);
  if (id == ParamId::kJointTorqueLimit &&
      control.supervisor.torque_max == app_->config().supervisor.torque_max) {
    config_ = node;  // torque_max already within: nothing for the tick to apply
    return SendParam(id, ParamStatus::kOk);
  }
  const RequestTag tag = Tag(Origin::kParam, static_cast<std::uint16_t>(id));
  const CommandOutcome o = app_->Configure(control, tag);
  if (o.result != CommandOutcomeCode::kAccepted) return Answer(tag, o);
  // A tightened joint torque limit holds from now on; the tick applies torque_max.
  config_ = node;
  config_change_pending_ = true;
}

}  // namespace mjc::app
