// Calibration records over ISO-TP: reassembled, decoded with the record's checks, handed
// to the service (the tick applies it, idle only; the service keeps it in the store once
// applied), and answered with a two-byte single frame [result, detail].
#include "mjc/app/can_node.h"

namespace mjc::app {
using protocol::CalibrationResult;

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
  const protocol::IsoTpEvent event = isotp_.Handle(frame, service_->clock().ms(), &flow);
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
  service_->Upload(record);  // answered by its report (kCalibrationDone)
}

void CanNode::PollUpload() {
  if (isotp_.Poll(service_->clock().ms()) == protocol::IsoTpEvent::kTimeout) {
    ++counters_.isotp_errors;
    ReplyCalibration(CalibrationResult::kReassemblyError,
                     static_cast<std::uint8_t>(protocol::IsoTpEvent::kTimeout));
  }
}

}  // namespace mjc::app
