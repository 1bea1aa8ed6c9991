// The host's CAN links without a CAN kernel: the in-process bus (delivery to the other
// links in order, filters, timeouts) and SocketCAN's refusal with a reason where the
// kernel or the interface is missing; and the board client on such a link, which
// reassembles window summaries from their five frames; and the trial tables and
// windows.csv made of those windows. The real SocketCAN and ISO-TP paths run against
// Debian's kernel in tests/kernel.
#include "mjc/host/can_link.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <span>
#include <sstream>
#include <utility>

#include "mjc/host/board_client.h"
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
