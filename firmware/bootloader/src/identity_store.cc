#include "mjc/boot/identity_store.h"

#include <array>

namespace mjc::boot {
namespace {

constexpr bool SameCode(IdentityResult a, RecordResult b) {
  return static_cast<int>(a) == static_cast<int>(b);
}
static_assert(SameCode(IdentityResult::kOk, RecordResult::kOk));
static_assert(SameCode(IdentityResult::kFlashError, RecordResult::kFlashError));
static_assert(SameCode(IdentityResult::kVerifyFailed, RecordResult::kVerifyFailed));

bool Valid(const BoardIdentity& id) {
  return id.node >= 1 && id.node <= 8 && id.hardware_revision != 0;
}

bool AcceptPayload(std::span<const std::uint8_t> payload) {
  return Valid({.node = payload[0], .hardware_revision = payload[1]});
}

}  // namespace

IdentityStore::IdentityStore(hal::Flash* flash, std::uint32_t page_a,
                             std::uint32_t page_b)
    : pages_(flash, page_a, page_b, kFormat, AcceptPayload) {}

std::optional<IdentityStore::Loaded> IdentityStore::Load() const {
  std::array<std::uint8_t, kFormat.payload_bytes> payload{};
  const auto found = pages_.Load(payload);
  if (!found) return std::nullopt;
  return Loaded{{.node = payload[0], .hardware_revision = payload[1]},
                found->sequence,
                found->page};
}

IdentityResult IdentityStore::Save(const BoardIdentity& identity) {
  if (!Valid(identity)) return IdentityResult::kInvalid;
  std::array<std::uint8_t, kFormat.payload_bytes> payload{};
  payload[0] = identity.node;
  payload[1] = identity.hardware_revision;
  return static_cast<IdentityResult>(pages_.Save(payload));
}

}  // namespace mjc::boot
