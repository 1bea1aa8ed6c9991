// A small record kept in two flash pages (A/B) so that a power cut at any point of a
// save leaves the previous record or the new one, never neither. The board keeps two
// such records: its identity (identity_store.h, read by the bootloader and the
// application) and its calibration (mjc/app/calibration_store.h). Each page holds at
// most one record (little-endian, 8-byte aligned; P is the format's payload length):
//
//   offset  size
//        0     4  magic (which record this is)
//        4     2  version
//        6     2  payload length P
//        8     4  sequence number (wraps; newer = positive wrapping difference)
//       12     4  reserved, 0
//       16     P  payload
//     16+P     4  CRC-32 of bytes 0..15+P
//     20+P     4  commit mark
//
// A save erases the page that does not hold the newest valid record, programs bytes
// 0..15+P and then the CRC + commit double-word last: the record becomes valid in one
// program operation (the STM32G4 programs a double-word at once), so a power cut
// leaves the old record or the new one. A page counts when its header, CRC and commit
// check out and the caller accepts its payload; the newest such page wins.
//
// A page the flash cannot read (an ECC double error: the STM32G4 leaves one in every
// double word of an erase or program a power cut interrupted, RM0440 §5.3) counts as
// holding no record, so the other page's record wins; the next save erases it (a save
// always writes the page that does not hold the newest valid record). unreadable()
// names such pages for the board's report.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>

#include "hal/flash.h"

namespace mjc::boot {

struct RecordFormat {
  std::uint32_t magic = 0;
  std::uint16_t version = 0;
  std::uint16_t payload_bytes = 0;  // a multiple of 8, at most RecordPages::kMaxPayload
  std::uint32_t commit = 0;
};

// Stable codes (the stores' own result enums keep these numbers).
enum class RecordResult : std::uint8_t {
  kOk = 0,
  kFlashError = 1,    // erase or program failed (power, hardware)
  kVerifyFailed = 2,  // read back differs from what was written
};

class RecordPages {
 public:
  static constexpr std::size_t kHeaderBytes = 16;
  static constexpr std::size_t kTrailerBytes = 8;  // CRC-32 and the commit mark
  static constexpr std::size_t kMaxPayload = 48;   // the calibration record's
  // Whether a payload that arrived intact is one the caller can use.
  using Accept = bool (*)(std::span<const std::uint8_t> payload);

  static constexpr std::size_t RecordBytes(const RecordFormat& format) {
    return kHeaderBytes + format.payload_bytes + kTrailerBytes;
  }

  // `format.payload_bytes` must be a multiple of 8 and at most kMaxPayload (checked by
  // the stores' static_asserts); `accept` is called on every intact payload read.
  RecordPages(hal::Flash* flash, std::uint32_t page_a, std::uint32_t page_b,
              const RecordFormat& format, Accept accept)
      : flash_(flash), pages_{page_a, page_b}, format_(format), accept_(accept) {}

  struct Found {
    std::uint32_t sequence = 0;
    std::uint32_t page = 0;
  };

  // The newest valid record: its payload copied into `payload` (format.payload_bytes
  // long), or nullopt when neither page holds one (`payload` then untouched).
  std::optional<Found> Load(std::span<std::uint8_t> payload) const;

  // Writes `payload` (format.payload_bytes long) as the newest record. On failure the
  // previous record is still the newest valid one.
  RecordResult Save(std::span<const std::uint8_t> payload);

  // Which pages the last Load or Save found unreadable: bit 0 page A, bit 1 page B.
  std::uint8_t unreadable() const { return unreadable_; }

 private:
  std::optional<Found> ReadPage(std::uint32_t page,
                                std::span<std::uint8_t> payload) const;

  hal::Flash* flash_;
  std::uint32_t pages_[2];
  RecordFormat format_;
  Accept accept_;
  mutable std::uint8_t unreadable_ = 0;
};

}  // namespace mjc::boot
