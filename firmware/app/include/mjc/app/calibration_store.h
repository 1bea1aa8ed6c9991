// Power-fail-safe calibration storage in two flash pages (A/B). Each page holds at most
// one record (little-endian, 8-byte aligned):
//
//   offset size
//        0    4 magic 'MJCS'
//        4    2 schema version (1)
//        6    2 payload length (48)
//        8    4 sequence number (wraps; newer = positive wrapping difference)
//       12    4 reserved, 0
//       16   48 payload: the calibration record (protocol/calibration_record.h)
//       64    4 CRC-32 of bytes 0..63
//       68    4 commit mark 0xC0DEC0DE
//
// A save erases the page that does not hold the newest valid record, programs bytes
// 0..63, and programs the CRC + commit double-word last: a record becomes valid in one
// program operation, so a power cut at any point leaves the old record or the new one.
// At boot the newest valid record wins; with none the board stays uncalibrated.
// Writes happen only while the bridge is disabled (flash programming stalls the CPU's
// flash reads on the G474) — the caller's duty, enforced by the app (idle only).
#pragma once

#include <cstdint>
#include <optional>

#include "hal/flash.h"
#include "mjc/protocol/calibration_record.h"

namespace mjc::app {

enum class StoreResult : std::uint8_t {
  kOk = 0,
  kFlashError = 1,    // erase or program failed (power, hardware)
  kVerifyFailed = 2,  // read back differs from what was written
};

class CalibrationStore {
 public:
  static constexpr std::uint32_t kMagic = 0x53434A4Du;  // "MJCS"
  static constexpr std::uint16_t kVersion = 1;
  static constexpr std::uint32_t kCommit = 0xC0DEC0DEu;
  static constexpr std::size_t kRecordBytes = 72;

  CalibrationStore(hal::Flash* flash, std::uint32_t page_a, std::uint32_t page_b)
      : flash_(flash), pages_{page_a, page_b} {}

  struct Loaded {
    protocol::CalibrationRecord record;
    std::uint32_t sequence = 0;
    std::uint32_t page = 0;
  };

  // The newest valid record, or nullopt when neither page holds one.
  std::optional<Loaded> Load() const;

  // Writes `record` as the newest. On failure the previous record is still the newest
  // valid one (the pages were written in an order that guarantees it).
  StoreResult Save(const protocol::CalibrationRecord& record);

 private:
  std::optional<Loaded> ReadPage(std::uint32_t page) const;

  hal::Flash* flash_;
  std::uint32_t pages_[2];
};

class JointApp;

// At boot: hands the newest valid stored calibration to `app` (idle, just constructed;
// it takes effect at the first tick). Returns the loaded record; nullopt leaves the
// board uncalibrated.
std::optional<CalibrationStore::Loaded> RestoreCalibration(JointApp& app,
                                                           const CalibrationStore& store);

}  // namespace mjc::app
