// The host's CAN links without a CAN kernel: the in-process bus (delivery to the other
// links in order, filters, timeouts) and SocketCAN's refusal with a reason where the
// kernel or the interface is missing; the board client on such links (window summaries
// reassembled from their five frames, the host heartbeat's cadence); the candump log
// format; and the trial tables and windows.csv made of board windows. The real SocketCAN
// and ISO-TP paths run against Debian's kernel in tests/kernel.
#include "mjc/host/can_link.h"

#include <gtest/gtest.h>
#include <linux/can.h>
#include <linux/can/error.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <optional>
#include <span>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "mjc/host/board_client.h"
#include "mjc/host/candump.h"
#include "mjc/host/trial_report.h"
#include "mjc/protocol/codec.h"

namespace {

using namespace mjc;
using namespace mjc::host;

protocol::CanFrame Frame(std::uint32_t id, std::uint8_t byte) {
  protocol::CanFrame f;
  f.id = id;
  f.length = 1;
  f.data[0] = byte;
  return f;
}

TEST(InProcessBus, DeliversToTheOtherLinksInOrder) {
  auto bus = InProcessBus::Create();
  auto a = bus->Connect();
  auto b = bus->Connect();
  auto c = bus->Connect();
  std::string why;
  for (std::uint8_t i = 0; i < 10; ++i) ASSERT_TRUE(a->Send(Frame(0x201, i), &why));
  for (std::uint8_t i = 0; i < 10; ++i) {
    const auto got_b = b->Receive(100);
    const auto got_c = c->Receive(100);
    ASSERT_TRUE(got_b && got_c);
    EXPECT_EQ(got_b->frame.data[0], i);
    EXPECT_EQ(got_c->frame.data[0], i);
  }
  EXPECT_FALSE(a->Receive(0));  // a sender does not hear itself
  EXPECT_EQ(a->stats().sent, 10u);
  EXPECT_EQ(b->stats().received, 10u);
}

TEST(InProcessBus, FiltersAndTimeouts) {
  auto bus = InProcessBus::Create();
  auto host = bus->Connect();
  auto board = bus->Connect();
  std::string why;
  // The host listens to node 3 only.
  const IdFilter node3{0x003, 0x00F};
  ASSERT_TRUE(host->SetFilters({&node3, 1}, &why));
  board->Send(Frame(protocol::MakeId(0x30, 2), 1), &why);
  board->Send(Frame(protocol::MakeId(0x30, 3), 2), &why);
  const auto got = host->Receive(100);
  ASSERT_TRUE(got);
  EXPECT_EQ(got->frame.data[0], 2);
  const auto none = host->Receive(20);
  EXPECT_FALSE(none);
  EXPECT_EQ(none.status, ReceiveStatus::kTimeout);  // a quiet bus is not an error
}

TEST(InProcessBus, TimestampsAreMicrosecondsOfTheRealtimeClock) {
  auto bus = InProcessBus::Create();
  auto a = bus->Connect();
  auto b = bus->Connect();
  std::string why;
  const auto before = std::chrono::duration_cast<std::chrono::microseconds>(
                          std::chrono::system_clock::now().time_since_epoch())
                          .count();
  ASSERT_TRUE(a->Send(Frame(0x201, 1), &why));
  const auto got = b->Receive(100);
  ASSERT_TRUE(got);
  EXPECT_GE(got->timestamp_us, before);
  EXPECT_LT(got->timestamp_us, before + 1000000);
}

TEST(SocketCanLink, RefusesWithAReasonWhenThereIsNoCan) {
  std::string why;
  // This build machine's kernel has no CAN (tests/kernel boots one that has); on a
  // machine with CAN the interface name below does not exist either.
  auto link = SocketCanLink::Open("mjcnosuchcan0", &why);
  EXPECT_EQ(link, nullptr);
  EXPECT_FALSE(why.empty());
  EXPECT_TRUE(why.find("CAN") != std::string::npos ||
              why.find("mjcnosuchcan0") != std::string::npos)
      << why;
  auto isotp = IsoTpLink::Open("", 0x3E1, 0x3F1, &why);
  EXPECT_EQ(isotp, nullptr);
  EXPECT_NE(why.find("interface name"), std::string::npos) << why;
}

// ---------------------------------------------------------------------------------
// Window summaries through BoardClient: five frames a window, header first.

constexpr std::uint8_t kNode = 1;

// Window `repetition`'s five frames as the board sends them; every value is derived
// from the repetition, so a window mixed from two would show.
std::array<protocol::CanFrame, 5> WindowFrames(std::uint16_t repetition) {
  protocol::WindowHeader h;
  h.motion = Motion::kFlexion;
  h.repetition = repetition;
  h.eta_valid = true;
  h.eta_percent = Ratio::Quantize(40.0 + repetition);
  protocol::WindowEnergy e;
  e.loading = protocol::WireEnergy::Quantize(0.001 * repetition);
  e.unloading = protocol::WireEnergy::Quantize(-0.0005 * repetition);
  protocol::WindowWork w;
  w.positive = protocol::WireEnergy::Quantize(0.002 * repetition);
  w.negative = protocol::WireEnergy::Quantize(-0.001 * repetition);
  protocol::WindowPeaks p;
  p.peak_power = Power::Quantize(0.001 * repetition);
  p.peak_torque = Torque::Quantize(0.01 * repetition);
  protocol::WindowTicks t;
  t.start_tick = 1000u * repetition;
  t.peak_offset = 100;
  t.end_offset = 200;
  return {protocol::Encode(h, kNode), protocol::Encode(e, kNode),
          protocol::Encode(w, kNode), protocol::Encode(p, kNode),
          protocol::Encode(t, kNode)};
}

class WindowAssembly : public ::testing::Test {
 protected:
  // Sends window `repetition` without the parts listed in `lost` (0 header … 4 ticks).
  void SendWindow(std::uint16_t repetition, std::initializer_list<int> lost = {}) {
    const auto frames = WindowFrames(repetition);
    for (int part = 0; part < 5; ++part) {
      if (std::find(lost.begin(), lost.end(), part) != lost.end()) continue;
      ASSERT_TRUE(board_->Send(frames[static_cast<std::size_t>(part)], &why_));
    }
  }
  std::vector<BoardWindow> Received() {
    EXPECT_TRUE(client_.Poll(50, &why_)) << why_;
    return client_.TakeWindows();
  }

  std::shared_ptr<InProcessBus> bus_ = InProcessBus::Create();
  std::unique_ptr<CanLink> board_ = bus_->Connect();
  std::unique_ptr<CanLink> host_ = bus_->Connect();
  BoardClient client_{host_.get(), kNode};
  std::string why_;
};

TEST_F(WindowAssembly, CompleteWindowsArriveWhole) {
  SendWindow(1);
  SendWindow(2);
  const auto windows = Received();
  ASSERT_EQ(windows.size(), 2u);
  const BoardWindow& w = windows[1];
  EXPECT_EQ(w.repetition, 2);
  EXPECT_TRUE(w.eta_valid);
  EXPECT_NEAR(w.eta_percent, 42.0, 1e-6);
  EXPECT_NEAR(w.loading_J, 0.002, 1e-7);
  EXPECT_NEAR(w.unloading_J, -0.001, 1e-7);
  EXPECT_NEAR(w.positive_J, 0.004, 1e-7);
  EXPECT_NEAR(w.negative_J, -0.002, 1e-7);
  EXPECT_NEAR(w.peak_power_W, 0.002, 1e-6);
  EXPECT_NEAR(w.peak_torque_Nm, 0.02, 1e-6);
  EXPECT_EQ(w.start_tick, 2000u);
  EXPECT_EQ(w.peak_tick, 2100u);
  EXPECT_EQ(w.end_tick, 2200u);
  EXPECT_EQ(client_.incomplete_windows(), 0u);
}

TEST_F(WindowAssembly, LostHeaderDropsTheWindowAndCountsIt) {
  SendWindow(1);
  SendWindow(2, {0});
  SendWindow(3);
  const auto windows = Received();
  ASSERT_EQ(windows.size(), 2u);
  EXPECT_EQ(windows[0].repetition, 1);
  EXPECT_EQ(windows[1].repetition, 3);
  EXPECT_NEAR(windows[0].loading_J, 0.001, 1e-7);  // not window 2's
  EXPECT_EQ(windows[1].start_tick, 3000u);
  EXPECT_EQ(client_.incomplete_windows(), 1u);
}

TEST_F(WindowAssembly, LostMiddleOrLastPartDropsTheWindow) {
  SendWindow(1, {2});  // no WindowWork
  SendWindow(2, {4});  // no WindowTicks: the next header ends it
  SendWindow(3);
  const auto windows = Received();
  ASSERT_EQ(windows.size(), 1u);
  EXPECT_EQ(windows[0].repetition, 3);
  EXPECT_NEAR(windows[0].positive_J, 0.006, 1e-7);
  EXPECT_EQ(client_.incomplete_windows(), 2u);
}

TEST_F(WindowAssembly, LostTicksAndNextHeaderDoNotMergeTwoWindows) {
  // Window 1's ticks and window 2's header lost: window 2's body would complete
  // window 1 if parts were only collected, not ordered.
  SendWindow(1, {4});
  SendWindow(2, {0});
  SendWindow(3);
  const auto windows = Received();
  ASSERT_EQ(windows.size(), 1u);
  EXPECT_EQ(windows[0].repetition, 3);
  EXPECT_EQ(client_.incomplete_windows(), 2u);
}

TEST_F(WindowAssembly, MalformedPartCountsAsLost) {
  auto frames = WindowFrames(1);
  frames[1].length = 7;  // WindowEnergy is 8 bytes
  for (const auto& f : frames) ASSERT_TRUE(board_->Send(f, &why_));
  EXPECT_TRUE(Received().empty());
  EXPECT_EQ(client_.malformed(), 1u);
  EXPECT_EQ(client_.incomplete_windows(), 1u);
}

// ---------------------------------------------------------------------------------
// The host heartbeat, on a link that runs a simulated clock: a receive that waits
// advances it by its whole timeout (the bus is quiet), and every sent frame is kept
// with the time it was sent.

class SimulatedLink final : public CanLink {
 public:
  using Time = std::chrono::steady_clock::time_point;
  Time now{};
  std::vector<std::pair<Time, protocol::CanFrame>> sent;

 private:
  bool DoSend(const protocol::CanFrame& frame, std::string*) override {
    sent.emplace_back(now, frame);
    return true;
  }
  ReceiveResult DoReceive(int timeout_ms, std::string*) override {
    now += std::chrono::milliseconds(timeout_ms);
    return {ReceiveStatus::kTimeout, {}};
  }
  bool DoSetFilters(std::span<const IdFilter>, std::string*) override { return true; }
};

class HostHeartbeatCadence : public ::testing::Test {
 protected:
  // The heartbeats sent so far: their times in ms since the start and sequences.
  std::vector<std::pair<long, int>> Heartbeats() const {
    std::vector<std::pair<long, int>> out;
    for (const auto& [time, frame] : link_.sent) {
      protocol::HostHeartbeat h;
      if (protocol::Decode(frame, &h) != protocol::DecodeError::kOk) continue;
      EXPECT_EQ(protocol::NodeOf(frame.id), kNode);
      const auto ms =
          std::chrono::duration_cast<std::chrono::milliseconds>(time - start_).count();
      out.emplace_back(static_cast<long>(ms), h.sequence);
    }
    return out;
  }

  SimulatedLink link_;
  const SimulatedLink::Time start_ = link_.now;
  BoardClient client_{&link_, kNode, HostHeartbeats::kSend, [this] { return link_.now; }};
  std::string why_;
};

TEST_F(HostHeartbeatCadence, EveryPeriodThroughOneLongPoll) {
  ASSERT_TRUE(client_.Poll(1000, &why_)) << why_;
  const auto beats = Heartbeats();
  // 0, 100, …, 1000 ms: the whole second, ends included, with consecutive sequences.
  ASSERT_EQ(beats.size(), 11u);
  for (std::size_t i = 0; i < beats.size(); ++i) {
    EXPECT_EQ(beats[i].first, 100 * static_cast<long>(i)) << "heartbeat " << i;
    EXPECT_EQ(beats[i].second, static_cast<int>(i)) << "heartbeat " << i;
  }
  EXPECT_EQ(link_.now - start_, std::chrono::milliseconds(1000));  // waited it all
}

TEST_F(HostHeartbeatCadence, KeepsItsCadenceAcrossShortPolls) {
  // A caller polling 30 ms at a time (as mjc monitor does in 5 ms steps): the
  // heartbeat goes out at the first poll after it is due, and the next one is due a
  // period after the last was, not after it went out, so the average stays 100 ms.
  for (int i = 0; i < 40; ++i) ASSERT_TRUE(client_.Poll(30, &why_)) << why_;
  const auto beats = Heartbeats();
  ASSERT_EQ(beats.size(), 13u);  // due at 0, 100, …, 1200: 1200 ms polled
  for (std::size_t i = 1; i < beats.size(); ++i) {
    EXPECT_LE(beats[i].first - beats[i - 1].first, 100 + 30) << "heartbeat " << i;
    EXPECT_GE(beats[i].first, 100 * static_cast<long>(i)) << "heartbeat " << i;
    EXPECT_LT(beats[i].first, 100 * static_cast<long>(i) + 30) << "heartbeat " << i;
  }
}

TEST_F(HostHeartbeatCadence, FlowWhileACommandWaitsForItsAnswer) {
  // No answer: the command waits out its 1000 ms in 10 ms polls, heartbeats on time.
  EXPECT_FALSE(client_.Command(protocol::CommandCode::kStop, 1000, &why_));
  EXPECT_NE(why_.find("did not answer"), std::string::npos) << why_;
  EXPECT_FALSE(client_.link_failed());
  const auto beats = Heartbeats();
  ASSERT_GE(beats.size(), 10u);
  for (std::size_t i = 0; i < beats.size(); ++i) {
    EXPECT_EQ(beats[i].first, 100 * static_cast<long>(i)) << "heartbeat " << i;
  }
}

TEST_F(HostHeartbeatCadence, NoneWhenOff) {
  BoardClient quiet(&link_, kNode, HostHeartbeats::kOff, [this] { return link_.now; });
  ASSERT_TRUE(quiet.Poll(1000, &why_)) << why_;
  EXPECT_TRUE(Heartbeats().empty());
  EXPECT_EQ(link_.now - start_, std::chrono::milliseconds(1000));
}

// ---------------------------------------------------------------------------------
// The candump log format. The lines below are what can-utils' candump -L (2020.11,
// Debian's) printed on vcan0 in the kernel VM for frames sent with cansend, timestamps
// included; the padded and suffixed ones are candump -L recording two interfaces, and
// candump -L -x.

struct RealLine {
  const char* text;
  std::int64_t timestamp_us;
  const char* interface;
  std::uint32_t can_id;
  bool fd;
  std::uint8_t flags;
  std::vector<std::uint8_t> data;  // a remote frame: empty, `length` its DLC
  std::uint8_t length;
  bool canonical;  // candump's own spelling of the frame: formats back identically
};

const RealLine kRealLines[] = {
    {"(1795253289.093369) vcan0 123#DEADBEEF",
     1795253289093369,
     "vcan0",
     0x123,
     false,
     0,
     {0xDE, 0xAD, 0xBE, 0xEF},
     4,
     true},
    {"(1795253289.169273) vcan0 7FF#",
     1795253289169273,
     "vcan0",
     0x7FF,
     false,
     0,
     {},
     0,
     true},
    {"(1795253289.214565) vcan0 000#0011223344556677",
     1795253289214565,
     "vcan0",
     0x000,
     false,
     0,
     {0x00, 0x11, 0x22, 0x33, 0x44, 0x55, 0x66, 0x77},
     8,
     true},
    {"(1795253289.251047) vcan0 12345678#CAFE",
     1795253289251047,
     "vcan0",
     0x12345678 | CAN_EFF_FLAG,
     false,
     0,
     {0xCA, 0xFE},
     2,
     true},
    {"(1795253289.287015) vcan0 1FFFFFFF#01",
     1795253289287015,
     "vcan0",
     0x1FFFFFFF | CAN_EFF_FLAG,
     false,
     0,
     {0x01},
     1,
     true},
    {"(1795253289.342033) vcan0 321#R",
     1795253289342033,
     "vcan0",
     0x321 | CAN_RTR_FLAG,
     false,
     0,
     {},
     0,
     true},
    {"(1795253289.399898) vcan0 321#R3",
     1795253289399898,
     "vcan0",
     0x321 | CAN_RTR_FLAG,
     false,
     0,
     {},
     3,
     true},
    {"(1795253289.439667) vcan0 00000321#R",
     1795253289439667,
     "vcan0",
     0x321 | CAN_EFF_FLAG | CAN_RTR_FLAG,
     false,
     0,
     {},
     0,
     true},
    {"(1795253289.486801) vcan0 123##4",
     1795253289486801,
     "vcan0",
     0x123,
     true,
     CANFD_FDF,
     {},
     0,
     true},
    {"(1795253289.520726) vcan0 123##5AABBCCDD",
     1795253289520726,
     "vcan0",
     0x123,
     true,
     CANFD_FDF | CANFD_BRS,
     {0xAA, 0xBB, 0xCC, 0xDD},
     4,
     true},
    {"(1795253289.550717) vcan0 123##7001122334455667788000000",
     1795253289550717,
     "vcan0",
     0x123,
     true,
     CANFD_FDF | CANFD_BRS | CANFD_ESI,
     {0x00, 0x11, 0x22, 0x33, 0x44, 0x55, 0x66, 0x77, 0x88, 0x00, 0x00, 0x00},
     12,
     true},
    {"(1795253289.617099) vcan0 031#0101",
     1795253289617099,
     "vcan0",
     0x031,
     false,
     0,
     {0x01, 0x01},
     2,
     true},
    {"(1795253306.359001) vcan0 20000004#0004000000000000",
     1795253306359001,
     "vcan0",
     CAN_ERR_FLAG | CAN_ERR_CRTL,
     false,
     0,
     {0x00, 0x04, 0, 0, 0, 0, 0, 0},
     8,
     true},
    {"(1795253298.770858)  vcan0 123#AA",
     1795253298770858,
     "vcan0",
     0x123,
     false,
     0,
     {0xAA},
     1,
     false},
    {"(1795253298.812247) vcan12 456#BB",
     1795253298812247,
     "vcan12",
     0x456,
     false,
     0,
     {0xBB},
     1,
     true},
    {"(1795253298.840401) vcan0 7FF#R8 T",
     1795253298840401,
     "vcan0",
     0x7FF | CAN_RTR_FLAG,
     false,
     0,
     {},
     8,
     false},
};

TEST(CandumpLine, RealCandumpLinesParseAndFormatBack) {
  for (const RealLine& want : kRealLines) {
    std::string why;
    const auto got = ParseCandumpLine(want.text, &why);
    ASSERT_TRUE(got) << want.text << ": " << why;
    EXPECT_EQ(got->timestamp_us, want.timestamp_us) << want.text;
    EXPECT_EQ(got->interface, want.interface) << want.text;
    EXPECT_EQ(got->can_id, want.can_id) << want.text;
    EXPECT_EQ(got->fd, want.fd) << want.text;
    EXPECT_EQ(got->flags, want.flags) << want.text;
    EXPECT_EQ(got->length, want.length) << want.text;
    EXPECT_EQ(got->len8_dlc, 0) << want.text;
    for (std::size_t i = 0; i < got->data.size(); ++i) {
      EXPECT_EQ(got->data[i], i < want.data.size() ? want.data[i] : 0)
          << want.text << " byte " << i;
    }
    if (want.canonical) {
      EXPECT_EQ(FormatCandumpLine(*got), want.text);
    }
    // Any line formats to one that parses back to the same frame.
    const auto again = ParseCandumpLine(FormatCandumpLine(*got), &why);
    ASSERT_TRUE(again) << FormatCandumpLine(*got) << ": " << why;
    EXPECT_EQ(*again, *got) << want.text;
  }
}

TEST(CandumpLine, WhatCansendSpellingsAndOtherWritersAdd) {
  std::string why;
  // cansend's '.' between bytes (candump prints them run together), lower-case hex,
  // a CRLF line end, a tab as the blank, a short seconds field, a received mark.
  const auto dotted = ParseCandumpLine("(1.000001)\tcan0 1ab#11.22.aa R\r\n", &why);
  ASSERT_TRUE(dotted) << why;
  EXPECT_EQ(dotted->timestamp_us, 1000001);
  EXPECT_EQ(dotted->interface, "can0");
  EXPECT_EQ(dotted->can_id, 0x1ABu);
  ASSERT_EQ(dotted->length, 3);
  EXPECT_EQ(dotted->data[2], 0xAA);
  EXPECT_EQ(FormatCandumpLine(*dotted), "(0000000001.000001) can0 1AB#1122AA");
  // Classical 8-byte frames with a raw DLC of 9..15 (newer candump: "_<dlc>").
  const auto dlc =
      ParseCandumpLine("(1699999999.123456) can0 123#0011223344556677_C", &why);
  ASSERT_TRUE(dlc) << why;
  EXPECT_EQ(dlc->length, 8);
  EXPECT_EQ(dlc->len8_dlc, 12);
  EXPECT_EQ(FormatCandumpLine(*dlc), "(1699999999.123456) can0 123#0011223344556677_C");
  const auto remote = ParseCandumpLine("(1699999999.123456) can0 123#R8_F", &why);
  ASSERT_TRUE(remote) << why;
  EXPECT_EQ(remote->length, 8);
  EXPECT_EQ(remote->len8_dlc, 15);
  EXPECT_EQ(FormatCandumpLine(*remote), "(1699999999.123456) can0 123#R8_F");
}

TEST(CandumpLine, MalformedLinesAreRefusedWithTheReason) {
  struct Case {
    std::string line;
    const char* reason;
  };
  const std::string ts = "(1699999999.123456) ";
  const std::vector<Case> cases = {
      {"", "no '(seconds.microseconds)' timestamp"},
      {"1699999999.123456 vcan0 123#00", "no '(seconds.microseconds)' timestamp"},
      {"(1699999999) vcan0 123#00", "want '(seconds.microseconds)'"},
      {"(1699999999.12345) vcan0 123#00", "exactly 6 digits of microseconds"},
      {"(1699999999.1234567) vcan0 123#00", "exactly 6 digits of microseconds, then ')'"},
      {"(1234567890123.000000) vcan0 123#00", "more than 12 digits of seconds"},
      {"(1699999999.123456)vcan0 123#00", "no blank after the timestamp"},
      {ts, "no interface"},
      {ts + "vcan0", "no frame after the interface"},
      {ts + "vcan0 ", "want an id of 3 or 8 hex digits"},
      {ts + "averyverylongname0 123#00", "longer than 15 characters"},
      {ts + std::string("vc\x01n0 123#00"), "control character"},
      {ts + "vcan0 1234#00", "want an id of 3 or 8 hex digits"},
      {ts + "vcan0 12G#00", "the id is not hex"},
      {ts + "vcan0 800#00", "an 11-bit id is at most 7FF"},
      {ts + "vcan0 40000123#00", "a 29-bit id is at most 1FFFFFFF"},
      {ts + "vcan0 E0000004#0000000000000000", "outside CAN_ERR_FLAG | CAN_ERR_MASK"},
      {ts + "vcan0 123#ABC", "odd number of hex digits"},
      {ts + "vcan0 123#001122334455667788", "more than 8 bytes for a classical frame"},
      {ts + "vcan0 123##1" + std::string(130, 'A'), "more than 64 bytes for a CAN FD"},
      {ts + "vcan0 123##", "one hex digit of flags"},
      {ts + "vcan0 123##G00", "one hex digit of flags"},
      {ts + "vcan0 123#R9", "DLC is one digit 0..8"},
      {ts + "vcan0 123#R3AA", "unexpected 'AA'"},
      {ts + "vcan0 20000004#R", "cannot be a remote frame"},
      {ts + "vcan0 20000004##0", "never CAN FD"},
      {ts + "vcan0 123#00112233445566_C", "must follow 8 bytes"},
      {ts + "vcan0 123#0011223344556677_8", "be 9..F"},
      {ts + "vcan0 123#11..22", "'.' in the data not followed by a byte"},
      {ts + "vcan0 123#11 X", "unexpected 'X' after the frame"},
      {ts + "vcan0 123#11 R T", "unexpected 'R T' after the frame"},
  };
  for (const Case& c : cases) {
    std::string why;
    std::optional<CandumpFrame> got;
    EXPECT_NO_THROW(got = ParseCandumpLine(c.line, &why)) << c.line;
    EXPECT_FALSE(got) << c.line;
    EXPECT_NE(why.find(c.reason), std::string::npos) << c.line << "\n  reason: " << why;
  }
}

TEST(CandumpLine, EveryKindOfFrameRoundTrips) {
  std::vector<CandumpFrame> frames;
  CandumpFrame f;
  f.timestamp_us = 1699999999000001;
  f.interface = "can1";
  f.can_id = 0x7FF;
  f.length = 8;
  for (std::uint8_t i = 0; i < 64; ++i) f.data[i] = static_cast<std::uint8_t>(17 * i);
  for (std::size_t i = 8; i < 64; ++i) f.data[i] = 0;
  frames.push_back(f);  // classical, 8 bytes
  f.len8_dlc = 15;
  frames.push_back(f);  // and a raw DLC
  f.len8_dlc = 0;
  f.can_id = 0x1FFFFFFF | CAN_EFF_FLAG;
  f.length = 0;
  f.data = {};
  frames.push_back(f);  // 29-bit, no data
  f.can_id = 0x100 | CAN_RTR_FLAG;
  f.length = 5;
  frames.push_back(f);  // remote, DLC 5
  f.can_id = CAN_ERR_FLAG | CAN_ERR_BUSOFF;
  f.length = 8;
  frames.push_back(f);  // bus-off error frame
  f.can_id = 0x042;
  f.fd = true;
  f.flags = CANFD_BRS | CANFD_FDF;
  f.length = 64;
  for (std::uint8_t i = 0; i < 64; ++i) f.data[i] = static_cast<std::uint8_t>(255 - i);
  frames.push_back(f);  // FD, 64 bytes
  for (const CandumpFrame& frame : frames) {
    const std::string line = FormatCandumpLine(frame);
    std::string why;
    const auto back = ParseCandumpLine(line, &why);
    ASSERT_TRUE(back) << line << ": " << why;
    EXPECT_EQ(*back, frame) << line;
  }
}

TEST(CandumpLine, OnlyStandardDataFramesAreTheProtocols) {
  std::string why;
  const auto ours =
      ParseCandumpLine("(1699999999.123456) vcan0 301#0102030405060708", &why);
  ASSERT_TRUE(ours) << why;
  const auto frame = ToProtocolFrame(*ours);
  ASSERT_TRUE(frame);
  EXPECT_EQ(frame->id, 0x301u);
  EXPECT_EQ(frame->length, 8);
  EXPECT_FALSE(frame->fd);
  EXPECT_EQ(frame->data[7], 0x08);
  for (const char* other : {"(1.000000) vcan0 00000301#01", "(1.000000) vcan0 301#R",
                            "(1.000000) vcan0 20000004#0004000000000000"}) {
    const auto line = ParseCandumpLine(other, &why);
    ASSERT_TRUE(line) << other << ": " << why;
    EXPECT_FALSE(ToProtocolFrame(*line)) << other;
  }
}

// ---------------------------------------------------------------------------------
// Trial tables and windows.csv.

BoardWindow Flexion(std::uint16_t repetition, double eta_percent, bool eta_valid) {
  BoardWindow w;
  w.motion = Motion::kFlexion;
  w.repetition = repetition;
  w.eta_percent = eta_percent;
  w.eta_valid = eta_valid;
  w.loading_J = 0.010;
  w.unloading_J = -0.005;
  w.positive_J = 0.011;
  w.negative_J = -0.006;
  return w;
}

TEST(TrialTables, InvalidEtaIsLeftOutOfTheStatisticsAndSaidSo) {
  // Five repetitions: the middle three flexions are 1, 2, 3; 3's η is invalid (its
  // value must not count), 0 and 4 are outside the analysis.
  TrialWindows trial{25.0,
                     5,
                     {Flexion(0, 10, true), Flexion(1, 40, true), Flexion(2, 50, true),
                      Flexion(3, 99, false), Flexion(4, 10, true)}};
  const std::string tables = TrialTables({trial}, true);
  // mean(40, 50) = 45, sample std = √((25 + 25) / 1) = 7.071.
  EXPECT_NE(tables.find("| 1 | 45.00% | 7.071% |"), std::string::npos) << tables;
  EXPECT_NE(tables.find("| overall | 45.00% | 7.071% |"), std::string::npos) << tables;
  EXPECT_NE(tables.find("leaves out 1 "), std::string::npos) << tables;
  // The amplitude table still counts the invalid window's energies (3 × 10 mJ).
  const std::string amplitude = TrialTables({trial}, false);
  EXPECT_NE(amplitude.find("| 25° | 10.000 ± 0.000 |"), std::string::npos) << amplitude;
  EXPECT_NE(amplitude.find("| 45.0% |"), std::string::npos) << amplitude;
}

TEST(TrialTables, NoValidEtaReadsNotAvailable) {
  TrialWindows trial{25.0, 3, {Flexion(1, 40, false)}};
  EXPECT_NE(TrialTables({trial}, true).find("| 1 | n/a | n/a |"), std::string::npos);
}

class WindowsCsv : public ::testing::Test {
 protected:
  void SetUp() override {
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  const std::filesystem::path dir_ =
      std::filesystem::temp_directory_path() / "mjc_windows_csv_test";
};

TEST_F(WindowsCsv, RoundTripsEveryWindowAndDerivesTheRepetitions) {
  BoardWindow extension = Flexion(4, 0, false);
  extension.motion = Motion::kExtension;
  const std::vector<TrialWindows> written = {
      {6.0, 5, {Flexion(0, 41.5, true), Flexion(3, 99, false), extension}},
      {8.0, 5, {Flexion(1, 47.25, true)}}};
  WriteWindowsCsv(written, dir_);
  std::string why;
  const auto read = ReadWindowsCsv(dir_, &why);
  ASSERT_TRUE(read) << why;
  ASSERT_EQ(read->size(), 2u);
  const TrialWindows& first = (*read)[0];
  EXPECT_EQ(first.amplitude_deg, 6.0);
  EXPECT_EQ(first.repetitions, 5);  // repetitions 0..4
  ASSERT_EQ(first.windows.size(), 3u);
  EXPECT_TRUE(first.windows[0].eta_valid);
  EXPECT_EQ(first.windows[0].eta_percent, 41.5);
  EXPECT_FALSE(first.windows[1].eta_valid);
  EXPECT_EQ(first.windows[1].positive_J, 0.011);
  EXPECT_EQ(first.windows[1].negative_J, -0.006);
  EXPECT_EQ(first.windows[2].motion, Motion::kExtension);
  EXPECT_EQ((*read)[1].repetitions, 2);  // only repetition 1 seen
  EXPECT_FALSE(SameAmplitude(*read));
}

TEST_F(WindowsCsv, AFileOfAnotherLayoutIsRefusedWithTheReason) {
  std::ofstream(dir_ / "windows.csv")
      << "trial,amplitude_deg,motion,repetition,eta_pct,loading_J,unloading_J,net_J,"
         "peak_power_W,peak_torque_Nm\n1,25,flexion,0,40,0.01,-0.005,0.005,0.01,0.1\n";
  std::string why;
  EXPECT_FALSE(ReadWindowsCsv(dir_, &why));
  EXPECT_NE(why.find("the header is not"), std::string::npos) << why;
}

TEST_F(WindowsCsv, AnUnknownMotionIsMalformed) {
  WriteWindowsCsv({{25.0, 5, {Flexion(1, 40, true)}}}, dir_);
  std::stringstream read;
  read << std::ifstream(dir_ / "windows.csv").rdbuf();
  std::string text = read.str();
  text.replace(text.find(",flexion,"), 9, ",sideways,");
  std::ofstream(dir_ / "windows.csv") << text;
  std::string why;
  EXPECT_FALSE(ReadWindowsCsv(dir_, &why));
  EXPECT_NE(why.find("line 2 is malformed"), std::string::npos) << why;
}

TEST_F(WindowsCsv, AnUnwritableFolderThrowsNamingTheFile) {
  const auto missing = dir_ / "no" / "such" / "folder";
  try {
    WriteWindowsCsv({}, missing);
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find((missing / "windows.csv").string()),
              std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("No such file"), std::string::npos) << e.what();
  }
}

}  // namespace
