// The board's ISO-TP receiver on frames built from ISO 15765-2 by hand: single frame;
// first frame + consecutive frames with the clear-to-send reply; sequence errors,
// overflow (flow control "overflow") and the N_Cr timeout dropping a transfer.
#include <cstdint>
#include <vector>

#include "mjc/protocol/isotp.h"
#include "vector_test.h"

namespace {

using namespace mjc::protocol;

constexpr std::uint32_t kRx = 0x3E1, kTx = 0x3F1;

CanFrame Raw(std::vector<std::uint8_t> bytes) {
  CanFrame f;
  f.id = kRx;
  f.length = static_cast<std::uint8_t>(bytes.size());
  for (std::size_t i = 0; i < bytes.size(); ++i) f.data[i] = bytes[i];
  return f;
}

// Segments `payload` into FF + CFs as a sender does (no padding, like Linux's default).
std::vector<CanFrame> Segment(const std::vector<std::uint8_t>& payload) {
  std::vector<CanFrame> frames;
  std::vector<std::uint8_t> ff = {static_cast<std::uint8_t>(0x10 | (payload.size() >> 8)),
                                  static_cast<std::uint8_t>(payload.size() & 0xFF)};
  ff.insert(ff.end(), payload.begin(), payload.begin() + 6);
  frames.push_back(Raw(ff));
  std::uint8_t seq = 1;
  for (std::size_t i = 6; i < payload.size();
       i += 7, seq = static_cast<std::uint8_t>((seq + 1) & 0xF)) {
    std::vector<std::uint8_t> cf = {static_cast<std::uint8_t>(0x20 | seq)};
    for (std::size_t k = i; k < payload.size() && k < i + 7; ++k)
      cf.push_back(payload[k]);
    frames.push_back(Raw(cf));
  }
  return frames;
}

std::vector<std::uint8_t> Payload(std::size_t n) {
  std::vector<std::uint8_t> p(n);
  for (std::size_t i = 0; i < n; ++i) p[i] = static_cast<std::uint8_t>(i * 13 + 5);
  return p;
}

MJC_VECTOR_TEST(IsoTp, SingleFrame) {
  IsoTpReceiver rx(kTx);
  CanFrame reply;
  VT_EXPECT_TRUE(rx.Handle(Raw({0x03, 0xAA, 0xBB, 0xCC}), 0, &reply) ==
                 IsoTpEvent::kComplete);
  VT_EXPECT_EQ(reply.length, 0);
  VT_EXPECT_EQ(rx.payload().size(), 3u);
  VT_EXPECT_EQ(rx.payload()[2], 0xCC);
}

MJC_VECTOR_TEST(IsoTp, MultiFrameWithFlowControl) {
  for (std::size_t n : {8u, 48u, 200u, 256u}) {
    IsoTpReceiver rx(kTx);
    const auto payload = Payload(n);
    const auto frames = Segment(payload);
    CanFrame reply;
    IsoTpEvent last = IsoTpEvent::kNone;
    for (std::size_t i = 0; i < frames.size(); ++i) {
      last = rx.Handle(frames[i], 10 * static_cast<std::uint32_t>(i), &reply);
      if (i == 0) {
        // Clear to send, block size 0, STmin 0, on the board's id.
        VT_EXPECT_EQ(reply.id, kTx);
        VT_EXPECT_EQ(reply.data[0], 0x30);
        VT_EXPECT_EQ(reply.data[1], 0);
      }
    }
    VT_EXPECT_TRUE(last == IsoTpEvent::kComplete);
    VT_EXPECT_EQ(rx.payload().size(), n);
    bool same = rx.payload().size() == n;
    for (std::size_t i = 0; same && i < n; ++i) same = rx.payload()[i] == payload[i];
    VT_EXPECT_TRUE(same);
  }
}

MJC_VECTOR_TEST(IsoTp, ErrorsDropTheTransfer) {
  CanFrame reply;
  // Sequence: CF 2 after the FF.
  IsoTpReceiver rx(kTx);
  auto frames = Segment(Payload(48));
  rx.Handle(frames[0], 0, &reply);
  VT_EXPECT_TRUE(rx.Handle(frames[2], 1, &reply) == IsoTpEvent::kSequenceError);
  VT_EXPECT_TRUE(rx.Handle(frames[1], 2, &reply) ==
                 IsoTpEvent::kMalformed);  // nothing open
  // Overflow: more than the buffer; flow control says so.
  auto big = Segment(Payload(300));
  VT_EXPECT_TRUE(rx.Handle(big[0], 3, &reply) == IsoTpEvent::kOverflow);
  VT_EXPECT_EQ(reply.data[0], 0x32);
  // Timeout: no CF within N_Cr.
  rx.Handle(frames[0], 100, &reply);
  VT_EXPECT_TRUE(rx.Poll(100 + IsoTpReceiver::kTimeoutMs) == IsoTpEvent::kNone);
  VT_EXPECT_TRUE(rx.Poll(101 + IsoTpReceiver::kTimeoutMs) == IsoTpEvent::kTimeout);
  VT_EXPECT_TRUE(rx.Handle(frames[1], 2000, &reply) == IsoTpEvent::kMalformed);
  // Malformed PCIs.
  VT_EXPECT_TRUE(rx.Handle(Raw({0x00}), 0, &reply) == IsoTpEvent::kMalformed);
  VT_EXPECT_TRUE(rx.Handle(Raw({0x08, 1, 2, 3, 4, 5, 6, 7}), 0, &reply) ==
                 IsoTpEvent::kMalformed);
  VT_EXPECT_TRUE(rx.Handle(Raw({0x30, 0, 0}), 0, &reply) == IsoTpEvent::kMalformed);
  VT_EXPECT_TRUE(rx.Handle(Raw({0x10, 0x05, 1, 2, 3, 4, 5, 6}), 0, &reply) ==
                 IsoTpEvent::kMalformed);
}

}  // namespace
