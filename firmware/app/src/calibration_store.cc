#include "mjc/app/calibration_store.h"

#include <array>

#include "mjc/app/joint_app.h"

namespace mjc::app {

namespace {

// An intact page counts only if its record is one the board accepts.
bool AcceptPayload(std::span<const std::uint8_t> payload) {
  protocol::CalibrationRecord record;
  std::uint8_t detail = 0;
  return protocol::DecodeCalibration(payload, &record, &detail) ==
         protocol::CalibrationResult::kAccepted;
}

}  // namespace

CalibrationStore::CalibrationStore(hal::Flash* flash, std::uint32_t page_a,
                                   std::uint32_t page_b)
    : pages_(flash, page_a, page_b, kFormat, AcceptPayload) {}

std::optional<CalibrationStore::Loaded> CalibrationStore::Load() const {
  std::array<std::uint8_t, kFormat.payload_bytes> payload{};
  const auto found = pages_.Load(payload);
  if (!found) return std::nullopt;
  Loaded loaded;
  std::uint8_t detail = 0;
  if (protocol::DecodeCalibration(payload, &loaded.record, &detail) !=
      protocol::CalibrationResult::kAccepted) {
    return std::nullopt;  // not reached: RecordPages took only accepted payloads
  }
  loaded.sequence = found->sequence;
  loaded.page = found->page;
  return loaded;
}

StoreResult CalibrationStore::Save(const protocol::CalibrationRecord& record) {
  return pages_.Save(protocol::EncodeCalibration(record));
}

std::optional<CalibrationStore::Loaded> RestoreCalibration(
    JointApp& app, const CalibrationStore& store) {
  const auto loaded = store.Load();
  if (!loaded) return std::nullopt;
  const protocol::CalibrationRecord& r = loaded->record;
  const CommandOutcome o =
      app.SetCalibration({r.backlash, r.sea_stiffness, r.joint_zero_count});
  if (o.result != CommandOutcomeCode::kAccepted) return std::nullopt;
  return loaded;
}

}  // namespace mjc::app
