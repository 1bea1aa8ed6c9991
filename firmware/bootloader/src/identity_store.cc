#include "mjc/boot/identity_store.h"

#include <array>

#include "mjc/protocol/crc32.h"
#include "mjc/protocol/little_endian.h"

namespace mjc::boot {
namespace {

using protocol::GetLe;
using protocol::PutLe;

bool Valid(const BoardIdentity& id) {
  return id.node >= 1 && id.node <= 8 && id.hardware_revision != 0;
}

}  // namespace

std::optional<IdentityStore::Loaded> IdentityStore::ReadPage(std::uint32_t page) const {
  std::array<std::uint8_t, kRecordBytes> b{};
  if (flash_->Read(page, 0, b) != hal::FlashResult::kOk) return std::nullopt;
  if (GetLe(&b[0], 4) != kMagic || GetLe(&b[4], 2) != kVersion || GetLe(&b[6], 2) != 8 ||
      GetLe(&b[28], 4) != kCommit ||
      GetLe(&b[24], 4) != protocol::Crc32(std::span<const std::uint8_t>(b).first(24))) {
    return std::nullopt;
  }
  Loaded loaded;
  loaded.identity = {.node = b[16], .hardware_revision = b[17]};
  if (!Valid(loaded.identity)) return std::nullopt;
  loaded.sequence = static_cast<std::uint32_t>(GetLe(&b[8], 4));
  loaded.page = page;
  return loaded;
}

std::optional<IdentityStore::Loaded> IdentityStore::Load() const {
  const auto a = ReadPage(pages_[0]);
  const auto b = ReadPage(pages_[1]);
  if (a && b) {
    // Newer = positive wrapping difference.
    return static_cast<std::int32_t>(b->sequence - a->sequence) > 0 ? b : a;
  }
  return a ? a : b;
}

IdentityResult IdentityStore::Save(const BoardIdentity& identity) {
  if (!Valid(identity)) return IdentityResult::kInvalid;
  const auto newest = Load();
  const std::uint32_t target =
      newest && newest->page == pages_[0] ? pages_[1] : pages_[0];
  const std::uint32_t sequence = newest ? newest->sequence + 1u : 1u;

  std::array<std::uint8_t, kRecordBytes> b{};
  PutLe(&b[0], kMagic, 4);
  PutLe(&b[4], kVersion, 2);
  PutLe(&b[6], 8, 2);
  PutLe(&b[8], sequence, 4);
  b[16] = identity.node;
  b[17] = identity.hardware_revision;
  PutLe(&b[24], protocol::Crc32(std::span<const std::uint8_t>(b).first(24)), 4);
  PutLe(&b[28], kCommit, 4);

  if (flash_->ErasePage(target) != hal::FlashResult::kOk)
    return IdentityResult::kFlashError;
  // Bytes 0..23 first, the CRC + commit double-word last.
  for (std::uint32_t offset = 0; offset < kRecordBytes; offset += 8) {
    if (flash_->ProgramDoubleWord(target, offset, GetLe(&b[offset], 8)) !=
        hal::FlashResult::kOk) {
      return IdentityResult::kFlashError;
    }
  }
  const auto written = ReadPage(target);
  if (!written || written->sequence != sequence) return IdentityResult::kVerifyFailed;
  return IdentityResult::kOk;
}

}  // namespace mjc::boot
