#include "mjc/app/calibration_store.h"

#include <array>
#include <cstring>

#include "mjc/app/joint_app.h"
#include "mjc/core/wrapping.h"
#include "mjc/protocol/little_endian.h"

namespace mjc::app {

std::optional<CalibrationStore::Loaded> CalibrationStore::ReadPage(
    std::uint32_t page) const {
  std::array<std::uint8_t, kRecordBytes> b{};
  if (flash_->Read(page, 0, b) != hal::FlashResult::kOk) return std::nullopt;
  if (protocol::GetLe(&b[0], 4) != kMagic || protocol::GetLe(&b[4], 2) != kVersion ||
      protocol::GetLe(&b[6], 2) != protocol::kCalibrationRecordSize ||
      protocol::GetLe(&b[68], 4) != kCommit ||
      protocol::GetLe(&b[64], 4) !=
          protocol::Crc32(std::span<const std::uint8_t>(b.data(), 64))) {
    return std::nullopt;
  }
  Loaded loaded;
  std::uint8_t detail = 0;
  if (protocol::DecodeCalibration(std::span<const std::uint8_t>(&b[16], 48),
                                  &loaded.record,
                                  &detail) != protocol::CalibrationResult::kAccepted) {
    return std::nullopt;  // intact but not a calibration the board accepts
  }
  loaded.sequence = static_cast<std::uint32_t>(protocol::GetLe(&b[8], 4));
  loaded.page = page;
  return loaded;
}

std::optional<CalibrationStore::Loaded> CalibrationStore::Load() const {
  const auto a = ReadPage(pages_[0]);
  const auto b = ReadPage(pages_[1]);
  if (a && b) return WrappingDelta(b->sequence, a->sequence) > 0 ? b : a;
  return a ? a : b;
}

StoreResult CalibrationStore::Save(const protocol::CalibrationRecord& record) {
  const auto newest = Load();
  const std::uint32_t target =
      newest && newest->page == pages_[0] ? pages_[1] : pages_[0];
  const std::uint32_t sequence =
      newest ? WrappingAdd<std::uint32_t>(newest->sequence, 1u) : 1u;

  std::array<std::uint8_t, kRecordBytes> b{};
  protocol::PutLe(&b[0], kMagic, 4);
  protocol::PutLe(&b[4], kVersion, 2);
  protocol::PutLe(&b[6], protocol::kCalibrationRecordSize, 2);
  protocol::PutLe(&b[8], sequence, 4);
  const auto payload = protocol::EncodeCalibration(record);
  std::memcpy(&b[16], payload.data(), payload.size());
  protocol::PutLe(&b[64], protocol::Crc32(std::span<const std::uint8_t>(b.data(), 64)),
                  4);
  protocol::PutLe(&b[68], kCommit, 4);

  if (flash_->ErasePage(target) != hal::FlashResult::kOk) return StoreResult::kFlashError;
  // Header and payload first, the CRC + commit double-word last.
  for (std::uint32_t offset = 0; offset < kRecordBytes; offset += 8) {
    if (flash_->ProgramDoubleWord(target, offset, protocol::GetLe(&b[offset], 8)) !=
        hal::FlashResult::kOk) {
      return StoreResult::kFlashError;
    }
  }
  const auto written = ReadPage(target);
  if (!written || written->sequence != sequence) return StoreResult::kVerifyFailed;
  return StoreResult::kOk;
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
