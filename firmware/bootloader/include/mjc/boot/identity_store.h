// The board's identity: its CAN node id and its hardware revision, kept in two flash
// pages of their own (A/B, beside the calibration's; identity pages 252-253 on the
// G474) so that no firmware update touches them. The bootloader reads it at every
// reset to answer with the board's node id and to check an image's hardware range; the
// application reads it for its node id (and writes it when commissioned: the hook in
// BOOTLOADER.md). Power-cut-safe as a RecordPages record (record_pages.h: the page
// layout and the save order) with magic 'MJID' (0x44494A4D), version 1, commit mark
// 0xC0DE1D1D and an 8-byte payload: node id (1..8), hardware revision (1..255), six
// reserved bytes, 0. The whole record is 32 bytes.
#pragma once

#include <cstdint>
#include <optional>

#include "hal/flash.h"
#include "mjc/boot/record_pages.h"

namespace mjc::boot {

struct BoardIdentity {
  std::uint8_t node = 0;               // 1..8
  std::uint8_t hardware_revision = 0;  // 1..255
};

// Stable codes; the first three are RecordResult's (checked in identity_store.cc).
enum class IdentityResult : std::uint8_t {
  kOk = 0,
  kFlashError = 1,    // erase or program failed (power, hardware)
  kVerifyFailed = 2,  // read back differs from what was written
  kInvalid = 3,       // node outside 1..8 or revision 0: nothing written
};

class IdentityStore {
 public:
  static constexpr RecordFormat kFormat{
      .magic = 0x44494A4Du, .version = 1, .payload_bytes = 8, .commit = 0xC0DE1D1Du};
  static_assert(RecordPages::RecordBytes(kFormat) == 32);

  IdentityStore(hal::Flash* flash, std::uint32_t page_a, std::uint32_t page_b);

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
  // Pages the last Load or Save could not read (RecordPages::unreadable).
  std::uint8_t unreadable_pages() const { return pages_.unreadable(); }

 private:
  RecordPages pages_;
};

}  // namespace mjc::boot
