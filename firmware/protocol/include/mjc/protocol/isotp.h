// ISO 15765-2 (ISO-TP) on the board, receiving side, over classical CAN frames: single
// frames, first + consecutive frames with flow control, sequence and timeout checks.
// The host uses the Linux kernel's implementation (CAN_ISOTP); the board has no
// kernel, so this is written here — small, bounded, no heap. Replies of up to 7 bytes
// go back as single frames (MakeSingleFrame).
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <span>

#include "mjc/protocol/can_frame.h"

namespace mjc::protocol {

enum class IsoTpEvent : std::uint8_t {
  kNone = 0,
  kComplete = 1,       // payload() holds a whole message
  kOverflow = 2,       // a first frame announced more than the buffer holds (FC sent)
  kSequenceError = 3,  // a consecutive frame out of order: transfer dropped
  kTimeout = 4,        // no consecutive frame for N_Cr: transfer dropped
  kMalformed = 5,      // a frame that is no valid ISO-TP PCI
};

class IsoTpReceiver {
 public:
  static constexpr std::size_t kCapacity = 256;      // a calibration record is 48 bytes
  static constexpr std::uint32_t kTimeoutMs = 1000;  // N_Cr

  // `tx_id`: the identifier flow-control frames go out on.
  explicit IsoTpReceiver(std::uint32_t tx_id) : tx_id_(tx_id) {}

  // A received frame (already matched to this channel's identifier) at now_ms. A flow
  // control frame to send back is written to *reply (length 0 when none).
  IsoTpEvent Handle(const CanFrame& frame, std::uint32_t now_ms, CanFrame* reply);

  // Called periodically: drops a transfer whose next frame is overdue.
  IsoTpEvent Poll(std::uint32_t now_ms);

  std::span<const std::uint8_t> payload() const { return {buffer_.data(), length_}; }

 private:
  std::uint32_t tx_id_;
  std::array<std::uint8_t, kCapacity> buffer_{};
  std::size_t length_ = 0;    // announced (or single-frame) length
  std::size_t received_ = 0;  // bytes so far
  std::uint8_t next_sequence_ = 1;
  bool receiving_ = false;
  std::uint32_t last_ms_ = 0;
};

// A single frame carrying 1..7 bytes on `id`.
CanFrame MakeSingleFrame(std::uint32_t id, std::span<const std::uint8_t> data);

}  // namespace mjc::protocol
