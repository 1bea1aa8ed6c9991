// Encoding and decoding of the messages in messages.h, derived from their signal
// lists. Decoding checks everything a frame can get wrong — function code, node,
// length, every field's range and enum values — and a refused frame changes nothing:
// the caller counts it and drops it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <tuple>
#include <type_traits>

#include "mjc/protocol/can_frame.h"
#include "mjc/protocol/crc32.h"
#include "mjc/protocol/little_endian.h"
#include "mjc/protocol/messages.h"

namespace mjc::protocol {

// Why a frame was refused. Stable numbers (counted per reason in the board's status).
enum class DecodeError : std::uint8_t {
  kOk = 0,
  kWrongFunction = 1,    // the identifier is not this message's
  kBadNode = 2,          // node id outside 1..8 (a broadcast message's: not 0)
  kWrongLength = 3,      // DLC differs from the message's length (or an FD message's
                         // frame is classical)
  kFieldOutOfRange = 4,  // a field's raw value is not legal for its type
  kFdFrame = 5,          // an FD frame where a classic one is defined
};
inline constexpr std::size_t kDecodeErrorCount =
    static_cast<std::size_t>(DecodeError::kFdFrame) + 1;

namespace codec_detail {

// The lengths a CAN FD frame can have above 8 bytes (DLC 9..15).
constexpr bool IsFdLength(unsigned n) {
  return n <= 8 || n == 12 || n == 16 || n == 20 || n == 24 || n == 32 || n == 48 ||
         n == 64;
}

// The first payload bit of the 64-bit word a signal is packed in: the whole payload's
// one word for a classical frame; the signal's own byte for an FD frame (the word then
// spans up to 8 bytes from there, fewer at the frame's end).
template <class M, class S>
constexpr unsigned WordStart(const S& s) {
  return Message<M>::kLength <= 8 ? 0u : (s.start / 8u) * 8u;
}

// Compile-time layout check: every signal inside the payload and inside its word, none
// overlapping; a classical message at most 8 bytes, an FD message a legal FD length.
template <class M>
constexpr bool LayoutIsValid() {
  std::uint64_t used[8] = {};
  bool ok = true;
  std::apply(
      [&](const auto&... s) {
        (
            [&] {
              if (s.bits == 0 || s.bits > 64 ||
                  s.start + s.bits > Message<M>::kLength * 8u ||
                  s.start - WordStart<M>(s) + s.bits > 64u) {
                ok = false;
                return;
              }
              for (unsigned bit = s.start; bit < s.start + s.bits; ++bit) {
                const std::uint64_t mask = std::uint64_t{1} << (bit % 64u);
                if (used[bit / 64u] & mask) ok = false;
                used[bit / 64u] |= mask;
              }
            }(),
            ...);
      },
      Message<M>::kSignals);
  return ok &&
         (Message<M>::kFd ? Message<M>::kLength > 8 && IsFdLength(Message<M>::kLength)
                          : Message<M>::kLength <= 8);
}

// The bytes of the word a signal starting at `word_start` is packed in.
template <class M>
constexpr int WordBytes(unsigned word_start) {
  const unsigned left = Message<M>::kLength - word_start / 8u;
  return static_cast<int>(left < 8u ? left : 8u);
}

}  // namespace codec_detail

// A broadcast message's identifier names no node (kEveryNode), whatever `node` says.
template <class M>
constexpr std::uint32_t IdOf(std::uint8_t node) {
  return MakeId(static_cast<std::uint8_t>(Message<M>::kFunction),
                Message<M>::kBroadcast ? kEveryNode : node);
}

// The frame of `message` from (board) or to (host) `node`; a broadcast message goes to
// every node (node ignored). Bytes no signal covers are zero.
template <class M>
constexpr CanFrame Encode(const M& message, std::uint8_t node) {
  static_assert(codec_detail::LayoutIsValid<M>(), "signals overlap or leave the frame");
  CanFrame frame;
  frame.id = IdOf<M>(node);
  frame.length = Message<M>::kLength;
  frame.fd = Message<M>::kFd;
  if constexpr (Message<M>::kLength <= 8) {
    std::uint64_t word = 0;
    std::apply([&](const auto&... s) { (s.Pack(message, &word), ...); },
               Message<M>::kSignals);
    PutLe(frame.data.data(), word, Message<M>::kLength);
  } else {
    const auto pack = [&](const auto& s) {
      const unsigned at = codec_detail::WordStart<M>(s);
      const int bytes = codec_detail::WordBytes<M>(at);
      std::uint8_t* p = frame.data.data() + at / 8u;
      std::uint64_t word = GetLe(p, bytes);
      s.Pack(message, &word, at);
      PutLe(p, word, bytes);
    };
    std::apply([&](const auto&... s) { (pack(s), ...); }, Message<M>::kSignals);
  }
  return frame;
}

// Decodes `frame` into *out when it is a valid M; *out is untouched otherwise. A
// classical message in an FD frame is kFdFrame; an FD message in a classical frame has
// the wrong length (no classical frame holds more than 8 bytes).
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
  if (frame.fd && !Message<M>::kFd) return DecodeError::kFdFrame;
  if (frame.fd != Message<M>::kFd || frame.length != Message<M>::kLength) {
    return DecodeError::kWrongLength;
  }
  M decoded{};
  bool ok = true;
  if constexpr (Message<M>::kLength <= 8) {
    const std::uint64_t word = GetLe(frame.data.data(), Message<M>::kLength);
    std::apply([&](const auto&... s) { ((ok = ok && s.Unpack(word, &decoded)), ...); },
               Message<M>::kSignals);
  } else {
    const auto unpack = [&](const auto& s) {
      const unsigned at = codec_detail::WordStart<M>(s);
      const std::uint64_t word =
          GetLe(frame.data.data() + at / 8u, codec_detail::WordBytes<M>(at));
      return s.Unpack(word, &decoded, at);
    };
    std::apply([&](const auto&... s) { ((ok = ok && unpack(s)), ...); },
               Message<M>::kSignals);
  }
  if (!ok) return DecodeError::kFieldOutOfRange;
  *out = decoded;
  return DecodeError::kOk;
}

// The name of a motion's configuration (ConfigDigest, messages.h): the CRC-32 of its
// frame's payload as encoded. Host and board encode the same values to the same bytes
// (every bit of a TrialConfig or SweepConfig is a field), so both compute the same name.
template <class M>
constexpr ConfigDigest ConfigDigestOf(const M& config) {
  static_assert(std::is_same_v<M, TrialConfig> || std::is_same_v<M, SweepConfig>);
  const CanFrame frame = Encode(config, kMinNode);
  return Crc32(std::span<const std::uint8_t>(frame.data.data(), frame.length));
}

}  // namespace mjc::protocol
