// Power-fail-safe calibration storage in two flash pages (A/B): a RecordPages record
// (mjc/boot/record_pages.h: the page layout and the save order that leaves the old
// record or the new one at any power cut) with magic 'MJCS' (0x53434A4D), schema
// version 1, commit mark 0xC0DEC0DE and the 48-byte calibration record
// (protocol/calibration_record.h) as its payload; 72 bytes in all. At boot the newest
// valid record wins; with none the board stays uncalibrated. Writes happen only while
// the bridge is disabled (flash programming stalls the CPU's flash reads on the G474) —
// the caller's duty, enforced by the app (idle only).
#pragma once

#include <cstdint>
#include <optional>

#include "hal/flash.h"
#include "mjc/boot/record_pages.h"
#include "mjc/protocol/calibration_record.h"

namespace mjc::app {

// What a save did: kOk, kFlashError (erase or program failed: power, hardware),
// kVerifyFailed (read back differs from what was written). Stable codes.
using StoreResult = boot::RecordResult;

class CalibrationStore {
 public:
  static constexpr boot::RecordFormat kFormat{
      .magic = 0x53434A4Du,
      .version = 1,
      .payload_bytes = static_cast<std::uint16_t>(protocol::kCalibrationRecordSize),
      .commit = 0xC0DEC0DEu};
  static_assert(boot::RecordPages::RecordBytes(kFormat) == 72);

  CalibrationStore(hal::Flash* flash, std::uint32_t page_a, std::uint32_t page_b);

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
  // Pages the last Load or Save could not read (RecordPages::unreadable).
  std::uint8_t unreadable_pages() const { return pages_.unreadable(); }

 private:
  boot::RecordPages pages_;
};

class JointApp;

// At boot: hands the newest valid stored calibration to `app` (idle, just constructed;
// it takes effect at the first tick). Returns the loaded record; nullopt leaves the
// board uncalibrated.
std::optional<CalibrationStore::Loaded> RestoreCalibration(JointApp& app,
                                                           const CalibrationStore& store);

}  // namespace mjc::app
