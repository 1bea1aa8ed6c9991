// The protocol codec on both platforms: every message round-trips random legal values
// bit for bit; a frame with the wrong identifier, node, length or FD flag, or with an
// illegal field value, is refused and leaves the output untouched; random payloads
// never crash the decoder.
#include <cstdint>
#include <tuple>

#include "mjc/protocol/codec.h"
#include "vector_test.h"

namespace {

using namespace mjc;
using namespace mjc::protocol;

// A random legal value of each field type.
template <class T>
T RandomValue(vt::Rng& rng);

template <class T>
requires IsFixed<T>::value T RandomValue(vt::Rng& rng) {
  if constexpr (sizeof(typename T::rep) == 8) return T::FromRaw(rng.NextI64());
  if constexpr (sizeof(typename T::rep) == 4) return T::FromRaw(rng.NextI32());
  if constexpr (sizeof(typename T::rep) == 2) return T::FromRaw(rng.NextI16());
}
template <class T>
requires std::is_integral_v<T> T RandomValue(vt::Rng& rng) {
  if constexpr (std::is_same_v<T, bool>) {
    return (rng.Next() & 1u) != 0;
  } else {
    return static_cast<T>(rng.Next());
  }
}
// Enums: draw raw values until a legal one comes up (all have legal values).
template <class T>
requires std::is_enum_v<T> T RandomValue(vt::Rng& rng) {
  for (;;) {
    const auto e = static_cast<T>(static_cast<std::underlying_type_t<T>>(rng.Next()));
    if (ValidEnumValue(e)) return e;
    // Sparse enums: also try small values, where their members live.
    const auto small =
        static_cast<T>(static_cast<std::underlying_type_t<T>>(rng.Next() % 0x400u));
    if (ValidEnumValue(small)) return small;
  }
}

template <class M>
M RandomMessage(vt::Rng& rng) {
  M m{};
  std::apply(
      [&](const auto&... s) {
        ((s.Ref(m) = RandomValue<std::remove_reference_t<decltype(s.Ref(m))>>(rng)), ...);
      },
      Message<M>::kSignals);
  return m;
}

template <class M>
bool FieldsEqual(const M& a, const M& b) {
  bool eq = true;
  std::apply([&](const auto&... s) { ((eq = eq && (s.Get(a) == s.Get(b))), ...); },
             Message<M>::kSignals);
  return eq;
}

template <class M>
int RoundTripFailures(vt::Rng& rng, int samples) {
  int failures = 0;
  for (int i = 0; i < samples; ++i) {
    const M sent = RandomMessage<M>(rng);
    const auto node = static_cast<std::uint8_t>(1 + rng.Next() % 8u);
    const CanFrame frame = Encode(sent, node);
    M got{};
    // A broadcast message names no node.
    const std::uint8_t to = Message<M>::kBroadcast ? kEveryNode : node;
    if (Decode(frame, &got) != DecodeError::kOk || !FieldsEqual(sent, got) ||
        NodeOf(frame.id) != to || frame.length != Message<M>::kLength ||
        frame.fd != Message<M>::kFd) {
      ++failures;
    }
  }
  return failures;
}

MJC_VECTOR_TEST(ProtocolCodec, EveryMessageRoundTripsBitForBit) {
  vt::Rng rng(501);
  int failures = 0;
  std::apply(
      [&](auto... m) { ((failures += RoundTripFailures<decltype(m)>(rng, 500)), ...); },
      AllMessages{});
  VT_EXPECT_EQ(failures, 0);
}

MJC_VECTOR_TEST(ProtocolCodec, LittleEndianLayoutAsTheDbcSays) {
  // TelemetryAngles: motor angle raw at bits 0..31, joint at 32..63, little-endian.
  TelemetryAngles m;
  m.motor = Angle::FromRaw(0x01020304);
  m.joint = Angle::FromRaw(-2);
  const CanFrame f = Encode(m, 3);
  VT_EXPECT_EQ(f.id, 0x203u);
  VT_EXPECT_EQ(f.data[0], 0x04);
  VT_EXPECT_EQ(f.data[3], 0x01);
  VT_EXPECT_EQ(f.data[4], 0xFE);
  VT_EXPECT_EQ(f.data[7], 0xFF);
  // Heartbeat flags share a byte: calibrated bit 8, bridge bit 9.
  Heartbeat h;
  h.calibrated = true;
  h.bridge_enabled = true;
  h.fault = Fault::kTorqueLimit;
  const CanFrame hf = Encode(h, 1);
  VT_EXPECT_EQ(hf.data[1], 0x03);
  VT_EXPECT_EQ(hf.data[2], 202);
}

// TelemetryAngleBatch, written out by hand from its table: a CAN FD frame of 48 bytes,
// identifier 0x25 << 4 | node; first_sample at bytes 0..3, then sample i's motor angle
// at bytes 4 + 8i and its joint angle at 8 + 8i (raw Q-format, little-endian); bytes
// 44..47 zero.
MJC_VECTOR_TEST(ProtocolCodec, AngleBatchLayoutByHand) {
  TelemetryAngleBatch m;
  m.first_sample = 0x0A0B0C0Du;
  m.motor[0] = Angle::FromRaw(0x01020304);
  m.joint[0] = Angle::FromRaw(-2);
  m.motor[2] = Angle::FromRaw(0x11223344);
  m.motor[4] = Angle::FromRaw(0x7FFFFFFF);
  m.joint[4] = Angle::FromRaw(-0x7FFFFFFF - 1);
  const CanFrame f = Encode(m, 3);
  VT_EXPECT_EQ(f.id, 0x253u);
  VT_EXPECT_TRUE(f.fd);
  VT_EXPECT_EQ(f.length, 48);
  const std::uint8_t want[48] = {
      0x0D, 0x0C, 0x0B, 0x0A,                          // first_sample
      0x04, 0x03, 0x02, 0x01, 0xFE, 0xFF, 0xFF, 0xFF,  // sample 0
      0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,  // sample 1
      0x44, 0x33, 0x22, 0x11, 0x00, 0x00, 0x00, 0x00,  // sample 2
      0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,  // sample 3
      0xFF, 0xFF, 0xFF, 0x7F, 0x00, 0x00, 0x00, 0x80,  // sample 4
      0x00, 0x00, 0x00, 0x00};                         // padding
  int differing = 0;
  for (std::size_t i = 0; i < 48; ++i) differing += f.data[i] != want[i] ? 1 : 0;
  VT_EXPECT_EQ(differing, 0);
  for (std::size_t i = 48; i < 64; ++i) differing += f.data[i] != 0 ? 1 : 0;
  VT_EXPECT_EQ(differing, 0);

  // The bytes by hand decode to the values.
  CanFrame by_hand;
  by_hand.id = 0x253u;
  by_hand.fd = true;
  by_hand.length = 48;
  for (std::size_t i = 0; i < 48; ++i) by_hand.data[i] = want[i];
  TelemetryAngleBatch got;
  VT_EXPECT_TRUE(Decode(by_hand, &got) == DecodeError::kOk);
  VT_EXPECT_EQ(got.first_sample, 0x0A0B0C0Du);
  VT_EXPECT_EQ(got.motor[0].raw(), 0x01020304);
  VT_EXPECT_EQ(got.joint[0].raw(), -2);
  VT_EXPECT_EQ(got.motor[2].raw(), 0x11223344);
  VT_EXPECT_EQ(got.motor[4].raw(), 0x7FFFFFFF);
  VT_EXPECT_EQ(got.joint[4].raw(), -0x7FFFFFFF - 1);

  // FD only, 48 bytes only; a refusal changes nothing.
  got.first_sample = 7;
  CanFrame bad = by_hand;
  bad.fd = false;
  VT_EXPECT_TRUE(Decode(bad, &got) == DecodeError::kWrongLength);
  bad = by_hand;
  bad.length = 32;
  VT_EXPECT_TRUE(Decode(bad, &got) == DecodeError::kWrongLength);
  bad = by_hand;
  bad.length = 64;
  VT_EXPECT_TRUE(Decode(bad, &got) == DecodeError::kWrongLength);
  bad = by_hand;
  bad.id = MakeId(static_cast<std::uint8_t>(Function::kTelemetryAngleBatch), 0);
  VT_EXPECT_TRUE(Decode(bad, &got) == DecodeError::kBadNode);
  VT_EXPECT_EQ(got.first_sample, 7u);
  // A board's message: its frames are signs of the board's life.
  VT_EXPECT_TRUE(SentByBoard(static_cast<std::uint8_t>(Function::kTelemetryAngleBatch)));
}

MJC_VECTOR_TEST(ProtocolCodec, MalformedFramesAreRefusedAndChangeNothing) {
  Heartbeat good;
  good.state = BoardState::kRunning;
  good.tick = 1234;
  const CanFrame frame = Encode(good, 2);
  Heartbeat out;
  out.tick = 99;  // must survive every refusal

  CanFrame f = frame;
  f.length = 7;
  VT_EXPECT_TRUE(Decode(f, &out) == DecodeError::kWrongLength);
  f = frame;
  f.id = MakeId(static_cast<std::uint8_t>(Function::kHeartbeat), 0);
  VT_EXPECT_TRUE(Decode(f, &out) == DecodeError::kBadNode);
  f.id = MakeId(static_cast<std::uint8_t>(Function::kHeartbeat), 9);
  VT_EXPECT_TRUE(Decode(f, &out) == DecodeError::kBadNode);
  f = frame;
  f.id = MakeId(static_cast<std::uint8_t>(Function::kFault), 2);
  VT_EXPECT_TRUE(Decode(f, &out) == DecodeError::kWrongFunction);
  f = frame;
  f.fd = true;
  VT_EXPECT_TRUE(Decode(f, &out) == DecodeError::kFdFrame);
  f = frame;
  f.data[0] = 9;  // no such board state
  VT_EXPECT_TRUE(Decode(f, &out) == DecodeError::kFieldOutOfRange);
  f = frame;
  f.data[2] = 7;  // fault code 7 does not exist
  f.data[3] = 0;
  VT_EXPECT_TRUE(Decode(f, &out) == DecodeError::kFieldOutOfRange);
  VT_EXPECT_EQ(out.tick, 99u);
  VT_EXPECT_TRUE(Decode(frame, &out) == DecodeError::kOk);
  VT_EXPECT_EQ(out.tick, 1234u);
}

// The emergency stop on the bus: identifier 0x000 (the highest priority there is), six
// bytes whose first four spell "STOP" in ASCII, then the session, little-endian.
MJC_VECTOR_TEST(ProtocolCodec, StopAllIsIdentifierZeroToEveryNode) {
  StopAll m;
  m.session = 0xBEEF;
  const CanFrame f = Encode(m, 5);  // the node is not the broadcast's to choose
  VT_EXPECT_EQ(f.id, 0x000u);
  VT_EXPECT_EQ(f.length, 6);
  VT_EXPECT_EQ(f.data[0], 'S');
  VT_EXPECT_EQ(f.data[1], 'T');
  VT_EXPECT_EQ(f.data[2], 'O');
  VT_EXPECT_EQ(f.data[3], 'P');
  VT_EXPECT_EQ(f.data[4], 0xEF);
  VT_EXPECT_EQ(f.data[5], 0xBE);
  StopAll out;
  out.session = 1;
  VT_EXPECT_TRUE(Decode(f, &out) == DecodeError::kOk);
  VT_EXPECT_EQ(out.session, 0xBEEF);
  VT_EXPECT_EQ(out.key, kStopAllKey);
  // The function code with a node id is no broadcast, and refused.
  CanFrame addressed = f;
  addressed.id = MakeId(static_cast<std::uint8_t>(Function::kStopAll), 3);
  out.session = 1;
  VT_EXPECT_TRUE(Decode(addressed, &out) == DecodeError::kBadNode);
  VT_EXPECT_EQ(out.session, 1);
  // Hosts send it; a board sends its WindowStart (a sign of its life).
  VT_EXPECT_TRUE(SentByBoard(static_cast<std::uint8_t>(Function::kWindowStart)));
  VT_EXPECT_TRUE(!SentByBoard(static_cast<std::uint8_t>(Function::kStopAll)));
}

MJC_VECTOR_TEST(ProtocolCodec, RandomFramesNeverCrashAndDecodeConsistently) {
  // Any payload either decodes to a message that re-encodes to the same payload bits it
  // uses, or is refused; nothing in between.
  vt::Rng rng(502);
  int inconsistent = 0, accepted = 0;
  for (int i = 0; i < 20000; ++i) {
    CanFrame f;
    f.id = MakeId(static_cast<std::uint8_t>(Function::kWindowHeader),
                  static_cast<std::uint8_t>(rng.Next() % 10u));
    f.length = static_cast<std::uint8_t>(rng.Next() % 9u);
    for (auto& b : f.data) b = static_cast<std::uint8_t>(rng.Next());
    // Three frames in four carry a legal fit_status (bits 25..31), or almost none
    // would decode; the fourth keeps the refusals of illegal ones in the draw.
    if (rng.Next() % 4u != 0) {
      f.data[3] = static_cast<std::uint8_t>((f.data[3] & 1u) | ((rng.Next() % 5u) << 1));
    }
    WindowHeader m;
    if (Decode(f, &m) == DecodeError::kOk) {
      ++accepted;
      const CanFrame again = Encode(m, NodeOf(f.id));
      // Every bit is used (eta_valid 24, fit_status 25..31): all must come back.
      bool same = true;
      for (std::size_t b = 0; b < 8; ++b) same = same && again.data[b] == f.data[b];
      if (!same) ++inconsistent;
    }
  }
  VT_EXPECT_EQ(inconsistent, 0);
  VT_EXPECT_TRUE(accepted > 0);
}

}  // namespace
