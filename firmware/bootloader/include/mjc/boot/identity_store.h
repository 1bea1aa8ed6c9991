// The board's identity: its CAN node id and its hardware revision, kept in two flash
// pages of their own (A/B, beside the calibration's; identity pages 252-253 on the
// G474) so that no firmware update touches them. The bootloader reads it at every
// reset to answer with the board's node id and to check an image's hardware range; the
// application reads it for its node id (and writes it when commissioned: the hook in
// BOOTLOADER.md). Power-cut-safe the way the calibration store is: each page holds at
// most one record (little-endian):
//
//   offset size
//        0    4 magic 'MJID' (0x44494A4D)
//        4    2 record version (1)
//        6    2 payload length (8)
//        8    4 sequence number (wraps; newer = positive wrapping difference)
//       12    4 reserved, 0
//       16    1 node id (1..8)
//       17    1 hardware revision (1..255)
//       18    6 reserved, 0
//       24    4 CRC-32 of bytes 0..23
//       28    4 commit mark 0xC0DE1D1D
//
// A save erases the page that does not hold the newest valid record, programs bytes
// 0..23 and then the CRC + commit double-word: the record becomes valid in one program
// operation, so a power cut leaves the old record or the new one.
#pragma once

#include <cstdint>
#include <optional>

#include "hal/flash.h"

namespace mjc::boot {

struct BoardIdentity {
  std::uint8_t node = 0;               // 1..8
  std::uint8_t hardware_revision = 0;  // 1..255
};

// Stable codes.
enum class IdentityResult : std::uint8_t {
  kOk = 0,
  kFlashError = 1,    // erase or program failed (power, hardware)
  kVerifyFailed = 2,  // read back differs from what was written
  kInvalid = 3,       // node outside 1..8 or revision 0: nothing written
};

class IdentityStore {
 public:
  static constexpr std::uint32_t kMagic = 0x44494A4Du;  // "MJID"
  static constexpr std::uint16_t kVersion = 1;
  static constexpr std::uint32_t kCommit = 0xC0DE1D1Du;
  static constexpr std::uint32_t kRecordBytes = 32;

  IdentityStore(hal::Flash* flash, std::uint32_t page_a, std::uint32_t page_b)
      : flash_(flash), pages_{page_a, page_b} {}

  struct Loaded {
    BoardIdentity identity;
    std::uint32_t sequence = 0;
    std::uint32_t page = 0;
  };

  // The newest valid record, or nullopt when neither page holds one.
  std::optional<Loaded> Load() const;
  // Writes `identity` as the newest; on failure the previous record is still the
  // newest valid one.
  IdentityResult Save(const BoardIdentity& identity);

 private:
  std::optional<Loaded> ReadPage(std::uint32_t page) const;

  hal::Flash* flash_;
  std::uint32_t pages_[2];
};

}  // namespace mjc::boot
