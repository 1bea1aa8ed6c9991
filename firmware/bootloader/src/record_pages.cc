#include "mjc/boot/record_pages.h"

#include <algorithm>
#include <array>

#include "mjc/core/wrapping.h"
#include "mjc/protocol/crc32.h"
#include "mjc/protocol/little_endian.h"

namespace mjc::boot {
namespace {

using protocol::GetLe;
using protocol::PutLe;

constexpr std::size_t kMaxRecordBytes =
    RecordPages::kHeaderBytes + RecordPages::kMaxPayload + RecordPages::kTrailerBytes;

}  // namespace

std::optional<RecordPages::Found> RecordPages::ReadPage(
    std::uint32_t page, std::span<std::uint8_t> payload) const {
  const std::size_t size = RecordBytes(format_);
  const std::size_t crc_at = kHeaderBytes + format_.payload_bytes;
  std::array<std::uint8_t, kMaxRecordBytes> buffer{};
  const std::span<std::uint8_t> b(buffer.data(), size);
  if (flash_->Read(page, 0, b) != hal::FlashResult::kOk) {
    unreadable_ = static_cast<std::uint8_t>(unreadable_ | (page == pages_[0] ? 1u : 2u));
    return std::nullopt;
  }
  if (GetLe(&b[0], 4) != format_.magic || GetLe(&b[4], 2) != format_.version ||
      GetLe(&b[6], 2) != format_.payload_bytes ||
      GetLe(&b[crc_at + 4], 4) != format_.commit ||
      GetLe(&b[crc_at], 4) != protocol::Crc32(b.first(crc_at))) {
    return std::nullopt;
  }
  const auto body = b.subspan(kHeaderBytes, format_.payload_bytes);
  if (!accept_(body)) return std::nullopt;  // intact but not a record the board uses
  std::copy(body.begin(), body.end(), payload.begin());
  return Found{static_cast<std::uint32_t>(GetLe(&b[8], 4)), page};
}

std::optional<RecordPages::Found> RecordPages::Load(
    std::span<std::uint8_t> payload) const {
  std::array<std::uint8_t, kMaxPayload> a_payload{}, b_payload{};
  unreadable_ = 0;
  const auto a = ReadPage(pages_[0], std::span(a_payload).first(format_.payload_bytes));
  const auto b = ReadPage(pages_[1], std::span(b_payload).first(format_.payload_bytes));
  const bool take_b = b && (!a || WrappingDelta(b->sequence, a->sequence) > 0);
  if (!a && !b) return std::nullopt;
  const auto& winner = take_b ? b_payload : a_payload;
  std::copy_n(winner.begin(), format_.payload_bytes, payload.begin());
  return take_b ? b : a;
}

RecordResult RecordPages::Save(std::span<const std::uint8_t> payload) {
  std::array<std::uint8_t, kMaxPayload> scratch{};
  const auto newest = Load(std::span(scratch).first(format_.payload_bytes));
  const std::uint32_t target =
      newest && newest->page == pages_[0] ? pages_[1] : pages_[0];
  const std::uint32_t sequence =
      newest ? WrappingAdd<std::uint32_t>(newest->sequence, 1u) : 1u;

  const std::size_t size = RecordBytes(format_);
  const std::size_t crc_at = kHeaderBytes + format_.payload_bytes;
  std::array<std::uint8_t, kMaxRecordBytes> buffer{};
  const std::span<std::uint8_t> b(buffer.data(), size);
  PutLe(&b[0], format_.magic, 4);
  PutLe(&b[4], format_.version, 2);
  PutLe(&b[6], format_.payload_bytes, 2);
  PutLe(&b[8], sequence, 4);
  std::copy_n(payload.begin(), format_.payload_bytes, &b[kHeaderBytes]);
  PutLe(&b[crc_at], protocol::Crc32(b.first(crc_at)), 4);
  PutLe(&b[crc_at + 4], format_.commit, 4);

  if (flash_->ErasePage(target) != hal::FlashResult::kOk)
    return RecordResult::kFlashError;
  // Header and payload first, the CRC + commit double-word last.
  for (std::uint32_t offset = 0; offset < size; offset += 8) {
    if (flash_->ProgramDoubleWord(target, offset, GetLe(&b[offset], 8)) !=
        hal::FlashResult::kOk) {
      return RecordResult::kFlashError;
    }
  }
  const auto written = ReadPage(target, std::span(scratch).first(format_.payload_bytes));
  if (!written || written->sequence != sequence) return RecordResult::kVerifyFailed;
  return RecordResult::kOk;
}

}  // namespace mjc::boot
