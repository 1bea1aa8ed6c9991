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

void CanNode::HandleParam(ParamId id, bool write, std::int32_t value) {
  // The decoder refused ids the list does not have.
  const protocol::ParamInfo& info = *protocol::FindParam(id);
  if (!write) return SendParam(id, ParamStatus::kOk);
  if (info.access == ParamAccess::kReadOnly) return SendParam(id, ParamStatus::kReadOnly);
  if (value < info.min_raw || value > info.max_raw) {
    return SendParam(id, ParamStatus::kOutOfRange);
  }
  ControlConfig control = app_->config();
  bool calibrated = false;
  if (info.access == ParamAccess::kNode) {
    (void)WriteParam(id, value, {&config_, &control, &calibrated});
    return SendParam(id, ParamStatus::kOk);
  }
  // The control configuration: applied by the tick, which judges it whole and answers.
  if (config_change_pending_) return SendParam(id, ParamStatus::kRefusedBusy);
  (void)WriteParam(id, value, {&config_, &control, &calibrated});
  const RequestTag tag = Tag(Origin::kParam, static_cast<std::uint16_t>(id));
  const CommandOutcome o = app_->Configure(control, tag);
  if (o.result != CommandOutcomeCode::kAccepted) return Answer(tag, o);
  config_change_pending_ = true;
}

}  // namespace mjc::app
