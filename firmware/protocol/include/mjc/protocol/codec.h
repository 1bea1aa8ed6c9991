// Encoding and decoding of the messages in messages.h, derived from their signal
// lists. Decoding checks everything a frame can get wrong — function code, node,
// length, every field's range and enum values — and a refused frame changes nothing:
// the caller counts it and drops it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <tuple>

#include "mjc/protocol/can_frame.h"
#include "mjc/protocol/little_endian.h"
#include "mjc/protocol/messages.h"

namespace mjc::protocol {

// Why a frame was refused. Stable numbers (counted per reason in the board's status).
enum class DecodeError : std::uint8_t {
  kOk = 0,
  kWrongFunction = 1,    // the identifier is not this message's
  kBadNode = 2,          // node id outside 1..8 (a broadcast message's: not 0)
  kWrongLength = 3,      // DLC differs from the message's length
  kFieldOutOfRange = 4,  // a field's raw value is not legal for its type
  kFdFrame = 5,          // an FD frame where a classic one is defined
};
inline constexpr std::size_t kDecodeErrorCount =
    static_cast<std::size_t>(DecodeError::kFdFrame) + 1;

namespace codec_detail {

// Compile-time layout check: every signal inside the payload, none overlapping.
template <class M>
constexpr bool LayoutIsValid() {
  std::uint64_t used = 0;
  bool ok = true;
  std::apply(
      [&](const auto&... s) {
        (
            [&] {
              if (s.bits == 0 || s.bits > 64 ||
                  s.start + s.bits > Message<M>::kLength * 8) {
                ok = false;
                return;
              }
              const std::uint64_t mask =
                  (s.bits == 64 ? ~std::uint64_t{0} : ((std::uint64_t{1} << s.bits) - 1u))
                  << s.start;
              if (used & mask) ok = false;
              used |= mask;
            }(),
            ...);
      },
      Message<M>::kSignals);
  return ok && Message<M>::kLength <= 8;
}

}  // namespace codec_detail

// A broadcast message's identifier names no node (kEveryNode), whatever `node` says.
template <class M>
constexpr std::uint32_t IdOf(std::uint8_t node) {
  return MakeId(static_cast<std::uint8_t>(Message<M>::kFunction),
                Message<M>::kBroadcast ? kEveryNode : node);
}

// The frame of `message` from (board) or to (host) `node`; a broadcast message goes to
// every node (node ignored).
template <class M>
constexpr CanFrame Encode(const M& message, std::uint8_t node) {
  static_assert(codec_detail::LayoutIsValid<M>(), "signals overlap or leave the frame");
  CanFrame frame;
  frame.id = IdOf<M>(node);
  frame.length = Message<M>::kLength;
  std::uint64_t word = 0;
  std::apply([&](const auto&... s) { (s.Pack(message, &word), ...); },
             Message<M>::kSignals);
  PutLe(frame.data.data(), word, Message<M>::kLength);
  return frame;
}

// Decodes `frame` into *out when it is a valid M; *out is untouched otherwise.
template <class M>
constexpr DecodeError Decode(const CanFrame& frame, M* out) {
  static_assert(codec_detail::LayoutIsValid<M>(), "signals overlap or leave the frame");
  if (frame.id > 0x7FFu ||
      FunctionOf(frame.id) != static_cast<std::uint8_t>(Message<M>::kFunction)) {
    return DecodeError::kWrongFunction;
  }
  const std::uint8_t node = NodeOf(frame.id);
  if (Message<M>::kBroadcast ? node != kEveryNode
                             : (node < kMinNode || node > kMaxNode)) {
    return DecodeError::kBadNode;
  }
  if (frame.fd) return DecodeError::kFdFrame;
  if (frame.length != Message<M>::kLength) return DecodeError::kWrongLength;
  const std::uint64_t word = GetLe(frame.data.data(), Message<M>::kLength);
  M decoded{};
  bool ok = true;
  std::apply([&](const auto&... s) { ((ok = ok && s.Unpack(word, &decoded)), ...); },
             Message<M>::kSignals);
  if (!ok) return DecodeError::kFieldOutOfRange;
  *out = decoded;
  return DecodeError::kOk;
}

}  // namespace mjc::protocol
