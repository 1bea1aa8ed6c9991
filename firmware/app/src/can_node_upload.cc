// Calibration records over ISO-TP: reassembled, decoded with the record's checks, handed
// to the app (which applies it in the tick, idle only), kept in the store once applied,
// and answered with a two-byte single frame [result, detail].
#include "mjc/app/can_node.h"

namespace mjc::app {
namespace {

using protocol::CalibrationResult;

CalibrationResult CalibrationResultOf(CommandOutcomeCode r) {
  switch (r) {
    case CommandOutcomeCode::kAccepted:
      return CalibrationResult::kAccepted;
    case CommandOutcomeCode::kRefusedInvalid:
      return CalibrationResult::kOutOfRange;
    case CommandOutcomeCode::kRefusedBusy:
      return CalibrationResult::kRefusedBusy;
    default:
      return CalibrationResult::kRefusedNotIdle;
  }
}

}  // namespace

void CanNode::ReplyCalibration(CalibrationResult result, std::uint8_t detail) {
  if (result == CalibrationResult::kAccepted) {
    ++counters_.calibrations_accepted;
  } else {
    ++counters_.calibrations_refused;
  }
  const std::uint8_t data[2] = {static_cast<std::uint8_t>(result), detail};
  Push(protocol::MakeSingleFrame(
      protocol::MakeId(static_cast<std::uint8_t>(protocol::Function::kIsoTpFromBoard),
                       config_.node),
      data));
}

void CanNode::HandleIsoTp(const protocol::CanFrame& frame) {
  protocol::CanFrame flow;
  const protocol::IsoTpEvent event = isotp_.Handle(frame, clock_.ms(), &flow);
  if (event == protocol::IsoTpEvent::kMalformed) {
    ++counters_.isotp_malformed;
    return;
  }
  ++counters_.handled;
  if (flow.length != 0) Push(flow);
  if (event == protocol::IsoTpEvent::kNone) return;
  if (event != protocol::IsoTpEvent::kComplete) {
    ++counters_.isotp_errors;
    return ReplyCalibration(CalibrationResult::kReassemblyError,
                            static_cast<std::uint8_t>(event));
  }
  protocol::CalibrationRecord record;
  std::uint8_t detail = 0;
  const CalibrationResult decoded = DecodeCalibration(isotp_.payload(), &record, &detail);
  if (decoded != CalibrationResult::kAccepted) return ReplyCalibration(decoded, detail);
  if (config_change_pending_ || leaving_) {
    return ReplyCalibration(CalibrationResult::kRefusedBusy, 0);
  }
  const CommandOutcome o = app_->SetCalibration(
      {record.backlash, record.sea_stiffness, record.joint_zero_count},
      Tag(Origin::kCalibration, 0));
  if (o.result != CommandOutcomeCode::kAccepted) return AnswerCalibration(o);
  pending_record_ = record;
  config_change_pending_ = true;
}

void CanNode::PollUpload() {
  if (isotp_.Poll(clock_.ms()) == protocol::IsoTpEvent::kTimeout) {
    ++counters_.isotp_errors;
    ReplyCalibration(CalibrationResult::kReassemblyError,
                     static_cast<std::uint8_t>(protocol::IsoTpEvent::kTimeout));
  }
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

}  // namespace mjc::app
