#include "mjc/protocol/isotp.h"

#include <algorithm>

namespace mjc::protocol {
namespace {

CanFrame FlowControl(std::uint32_t id, std::uint8_t status) {
  CanFrame f;
  f.id = id;
  f.length = 3;
  f.data[0] = static_cast<std::uint8_t>(0x30u | status);  // FS: 0 CTS, 2 overflow
  f.data[1] = 0;  // block size 0: the whole message without further flow control
  f.data[2] = 0;  // STmin 0: the board keeps up with back-to-back frames
  return f;
}

}  // namespace

IsoTpEvent IsoTpReceiver::Handle(const CanFrame& frame, std::uint32_t now_ms,
                                 CanFrame* reply) {
  reply->length = 0;
  if (frame.length == 0 || frame.fd) return IsoTpEvent::kMalformed;
  const std::uint8_t pci = frame.data[0];
  switch (pci >> 4) {
    case 0x0: {  // single frame: a new message, whatever was in progress
      const std::size_t n = pci & 0x0Fu;
      if (n == 0 || n > 7 || n + 1 > frame.length) return IsoTpEvent::kMalformed;
      std::copy_n(frame.data.begin() + 1, n, buffer_.begin());
      length_ = n;
      receiving_ = false;
      return IsoTpEvent::kComplete;
    }
    case 0x1: {  // first frame
      if (frame.length < 8) return IsoTpEvent::kMalformed;
      const std::size_t n = (static_cast<std::size_t>(pci & 0x0Fu) << 8) | frame.data[1];
      if (n < 8) return IsoTpEvent::kMalformed;  // would have been a single frame
      if (n > kCapacity) {
        receiving_ = false;
        *reply = FlowControl(tx_id_, 2);
        return IsoTpEvent::kOverflow;
      }
      std::copy_n(frame.data.begin() + 2, 6, buffer_.begin());
      length_ = n;
      received_ = 6;
      next_sequence_ = 1;
      receiving_ = true;
      last_ms_ = now_ms;
      *reply = FlowControl(tx_id_, 0);
      return IsoTpEvent::kNone;
    }
    case 0x2: {  // consecutive frame
      if (!receiving_) return IsoTpEvent::kMalformed;
      if ((pci & 0x0Fu) != next_sequence_) {
        receiving_ = false;
        return IsoTpEvent::kSequenceError;
      }
      const std::size_t n = std::min<std::size_t>(7, length_ - received_);
      if (frame.length < n + 1) {
        receiving_ = false;
        return IsoTpEvent::kMalformed;
      }
      std::copy_n(frame.data.begin() + 1, n,
                  buffer_.begin() + static_cast<std::ptrdiff_t>(received_));
      received_ += n;
      next_sequence_ = static_cast<std::uint8_t>((next_sequence_ + 1) & 0x0Fu);
      last_ms_ = now_ms;
      if (received_ == length_) {
        receiving_ = false;
        return IsoTpEvent::kComplete;
      }
      return IsoTpEvent::kNone;
    }
    default:
      return IsoTpEvent::kMalformed;  // flow control to a receiver, or reserved
  }
}

IsoTpEvent IsoTpReceiver::Poll(std::uint32_t now_ms) {
  if (receiving_ && now_ms - last_ms_ > kTimeoutMs) {
    receiving_ = false;
    return IsoTpEvent::kTimeout;
  }
  return IsoTpEvent::kNone;
}

CanFrame MakeSingleFrame(std::uint32_t id, std::span<const std::uint8_t> data) {
  CanFrame f;
  f.id = id;
  const std::size_t n = std::min<std::size_t>(data.size(), 7);
  f.length = static_cast<std::uint8_t>(n + 1);
  f.data[0] = static_cast<std::uint8_t>(n);
  std::copy_n(data.begin(), n, f.data.begin() + 1);
  return f;
}

}  // namespace mjc::protocol
