// The board client on links without a CAN kernel: window summaries reassembled from
// their five frames, the host heartbeat's cadence.
#include "mjc/host/board_client.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <initializer_list>
#include <memory>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "mjc/protocol/codec.h"

namespace {

using namespace mjc;
using namespace mjc::host;

// Window summaries through BoardClient: seven frames a window, header first.

constexpr std::uint8_t kNode = 1;

// Window `repetition`'s seven frames as the board sends them; every value is derived
// from the repetition, so a window mixed from two would show.
std::array<protocol::CanFrame, 7> WindowFrames(std::uint16_t repetition) {
  protocol::WindowHeader h;
  h.motion = Motion::kFlexion;
  h.repetition = repetition;
  h.eta_valid = true;
  h.eta_percent = Ratio::Quantize(40.0 + repetition);
  h.fit_status = InterfaceFitStatus::kOk;
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
  protocol::WindowFit fit;
  fit.stiffness = Stiffness::Quantize(4.0 + 0.1 * repetition);
  fit.damping = Damping::Quantize(0.2 + 0.01 * repetition);
  protocol::WindowFitResidual residual;
  residual.offset = Torque::Quantize(0.001 * repetition);
  residual.residual_rms = Torque::Quantize(0.0001 * repetition);
  return {protocol::Encode(h, kNode),       protocol::Encode(e, kNode),
          protocol::Encode(w, kNode),       protocol::Encode(p, kNode),
          protocol::Encode(t, kNode),       protocol::Encode(fit, kNode),
          protocol::Encode(residual, kNode)};
}

// Batched angle telemetry (CAN FD): one batch of five samples, sample n's angles
// derived from n, so a sample out of place would show.
protocol::CanFrame AngleBatch(std::uint32_t first_sample) {
  protocol::TelemetryAngleBatch b;
  b.first_sample = first_sample;
  for (std::size_t i = 0; i < b.motor.size(); ++i) {
    const auto n = static_cast<double>(first_sample + i);
    b.motor[i] = Angle::Quantize(0.001 * n);
    b.joint[i] = Angle::Quantize(-0.0005 * n);
  }
  return protocol::Encode(b, kNode);
}

TEST(AngleBatches, DecodeToTheSampleStreamAndALostFrameIsCounted) {
  auto bus = InProcessBus::Create();
  auto board = bus->Connect();
  auto host = bus->Connect();
  BoardClient client(host.get(), kNode);
  client.KeepAngles(true);
  std::string why;
  for (std::uint32_t batch = 0; batch < 6; ++batch) {
    if (batch == 3) continue;  // lost on the bus
    ASSERT_TRUE(board->Send(AngleBatch(5 * batch), &why)) << why;
  }
  ASSERT_TRUE(client.Poll(50, &why)) << why;
  const auto samples = client.TakeAngles();
  // Batches 0, 1, 2, 4, 5: samples 0..14 and 20..29, nothing made up for 15..19.
  ASSERT_EQ(samples.size(), 25u);
  for (std::size_t k = 0; k < samples.size(); ++k) {
    const double n = static_cast<double>(k < 15 ? k : k + 5);
    EXPECT_NEAR(samples[k].motor_rad, 0.001 * n, 1e-7) << k;
    EXPECT_NEAR(samples[k].joint_rad, -0.0005 * n, 1e-7) << k;
  }
  EXPECT_NEAR(client.status().motor_rad, 0.029, 1e-7);  // the last sample's
  const AngleSequence& seq = client.angle_sequence();
  EXPECT_EQ(seq.batches(), 5u);
  EXPECT_EQ(seq.lost_frames(), 1u);
  EXPECT_EQ(seq.lost_samples(), 5u);
  EXPECT_EQ(seq.restarts(), 0u);
  EXPECT_EQ(client.malformed(), 0u);

  // The board restarts (its count begins at 0 again): no loss, a restart.
  ASSERT_TRUE(board->Send(AngleBatch(0), &why)) << why;
  ASSERT_TRUE(board->Send(AngleBatch(5), &why)) << why;
  // A batch in a classical frame is refused and counted, not decoded.
  protocol::CanFrame classical = AngleBatch(10);
  classical.fd = false;
  classical.length = 8;
  ASSERT_TRUE(board->Send(classical, &why)) << why;
  ASSERT_TRUE(client.Poll(50, &why)) << why;
  EXPECT_EQ(client.TakeAngles().size(), 10u);
  EXPECT_EQ(seq.restarts(), 1u);
  EXPECT_EQ(seq.lost_frames(), 1u);
  EXPECT_EQ(client.malformed(), 1u);
}

TEST(AngleBatches, TheCountWrapsWithoutALossAndTwoLostFramesCountTwice) {
  AngleSequence seq;
  protocol::TelemetryAngleBatch b;
  b.first_sample = 0xFFFFFFFAu;  // 2^32 - 6: the next batch starts at 4294967295
  seq.OnBatch(b);
  b.first_sample = 0xFFFFFFFFu;
  seq.OnBatch(b);
  b.first_sample = 4;  // wrapped
  seq.OnBatch(b);
  EXPECT_EQ(seq.lost_frames(), 0u);
  b.first_sample = 19;  // 9 and 14 lost
  seq.OnBatch(b);
  EXPECT_EQ(seq.lost_frames(), 2u);
  EXPECT_EQ(seq.lost_samples(), 10u);
  EXPECT_EQ(seq.batches(), 4u);
  EXPECT_EQ(seq.restarts(), 0u);
}

class WindowAssembly : public ::testing::Test {
 protected:
  // Sends window `repetition` without the parts listed in `lost` (0 header … 4 ticks,
  // 5 fit, 6 residual).
  void SendWindow(std::uint16_t repetition, std::initializer_list<int> lost = {}) {
    const auto frames = WindowFrames(repetition);
    for (int part = 0; part < 7; ++part) {
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
  EXPECT_TRUE(w.fit_valid);
  EXPECT_NEAR(w.stiffness_Nm_rad, 4.2, 1e-6);
  EXPECT_NEAR(w.damping_Nms_rad, 0.22, 1e-6);
  EXPECT_NEAR(w.offset_Nm, 0.002, 1e-6);
  EXPECT_NEAR(w.residual_rms_Nm, 0.0002, 1e-6);
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
  SendWindow(2, {6});  // no WindowFitResidual: the next header ends it
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

TEST_F(WindowAssembly, UnknownFitStatusIsRefusedAndCounted) {
  auto frames = WindowFrames(1);
  frames[0].data[3] =
      static_cast<std::uint8_t>(frames[0].data[3] | (9 << 1));  // no status 9
  for (const auto& f : frames) ASSERT_TRUE(board_->Send(f, &why_));
  SendWindow(2);
  const auto windows = Received();
  ASSERT_EQ(windows.size(), 1u);
  EXPECT_EQ(windows[0].repetition, 2);
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
  EXPECT_NE(why_.find("node 1 is silent (is the board powered"), std::string::npos)
      << why_;
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
// Waits at the board's pace (Await): a board on a simulated clock that runs at
// `board_rate` board seconds per wall second and sends a frame every 100 ms of its own
// time — its heartbeat (carrying its tick) or, with heartbeats off, its angles — until
// `silent_after` of wall time.

class PacedBoardLink final : public CanLink {
 public:
  using Time = std::chrono::steady_clock::time_point;
  Time now{};
  double board_rate = 1.0;
  std::chrono::milliseconds silent_after = std::chrono::hours(1);
  bool heartbeats = true;
  // Sent instead of the board's frames: a host's heartbeat to the node (not the board).
  bool only_host_frames = false;
  // Sent instead: its bootloader's BootStatus (ready, held by a host's BootHold).
  bool bootloader = false;

  std::uint32_t BoardTick(Time t) const {
    const double wall_ms = std::chrono::duration<double, std::milli>(t - Time{}).count();
    return static_cast<std::uint32_t>(wall_ms * board_rate * 10.0);  // 10 kHz
  }

 private:
  bool DoSend(const protocol::CanFrame&, std::string*) override { return true; }
  ReceiveResult DoReceive(int timeout_ms, std::string*) override {
    const auto interval = std::chrono::duration_cast<std::chrono::steady_clock::duration>(
        std::chrono::duration<double, std::milli>(100.0 / board_rate));
    const Time until = now + std::chrono::milliseconds(timeout_ms);
    if (next_ > until || next_ - Time{} >= silent_after) {
      now = until;
      return {ReceiveStatus::kTimeout, {}};
    }
    now = std::max(now, next_);
    next_ += interval;
    ReceiveResult r;
    r.status = ReceiveStatus::kFrame;
    if (only_host_frames) {
      r.received.frame = protocol::Encode(protocol::HostHeartbeat{1}, kNode);
    } else if (bootloader) {
      protocol::BootStatus b;
      b.state = protocol::BootState::kReady;
      b.reason = protocol::StayReason::kHoldFrame;
      r.received.frame = protocol::Encode(b, kNode);
    } else if (heartbeats) {
      protocol::Heartbeat h;
      h.state = protocol::BoardState::kRunning;
      h.tick = BoardTick(now);
      r.received.frame = protocol::Encode(h, kNode);
    } else {
      r.received.frame = protocol::Encode(protocol::TelemetryAngles{}, kNode);
    }
    return r;
  }
  bool DoSetFilters(std::span<const IdFilter>, std::string*) override { return true; }
  Time next_{};
};

class AwaitAtTheBoardsPace : public ::testing::Test {
 protected:
  // Waits with `patience` until the board's clock shows `board_s` (never, when 0).
  bool AwaitBoardTime(double board_s, Patience patience) {
    const auto until = static_cast<std::uint32_t>(board_s * 10000);
    return client_.Await([&] { return board_s > 0 && client_.status().tick >= until; },
                         patience, &end_, &why_);
  }
  double WallSeconds() const {
    return std::chrono::duration<double>(link_.now - PacedBoardLink::Time{}).count();
  }

  PacedBoardLink link_;
  BoardClient client_{&link_, kNode, HostHeartbeats::kOff, [this] { return link_.now; }};
  WaitEnd end_{};
  std::string why_;
};

TEST_F(AwaitAtTheBoardsPace, ASlowBoardIsWaitedForAsLongAsItTalks) {
  // A tenth of real time: 5 s of its time take 50 s of this machine's, far beyond both
  // bounds were they wall time.
  link_.board_rate = 0.1;
  ASSERT_TRUE(AwaitBoardTime(5.0, {std::chrono::seconds(6), std::chrono::seconds(3)}))
      << why_;
  EXPECT_NEAR(WallSeconds(), 50.0, 1.1);
}

TEST_F(AwaitAtTheBoardsPace, TheBoardsOwnTimeBoundsIt) {
  ASSERT_FALSE(AwaitBoardTime(0, {std::chrono::seconds(2), std::chrono::seconds(3)}));
  EXPECT_EQ(end_, WaitEnd::kBoardTime);
  // Counted from the first heartbeat the wait saw (at 0), ended by the first one past
  // 2 s of board time.
  EXPECT_NEAR(WallSeconds(), 2.1, 0.001);
  EXPECT_NE(why_.find("2000 ms of its own time"), std::string::npos) << why_;
}

TEST_F(AwaitAtTheBoardsPace, AFastBoardEndsItInItsTimeNotOurs) {
  link_.board_rate = 4.0;
  ASSERT_FALSE(AwaitBoardTime(0, {std::chrono::seconds(2), std::chrono::seconds(3)}));
  EXPECT_EQ(end_, WaitEnd::kBoardTime);
  EXPECT_NEAR(WallSeconds(), 2.1 / 4.0, 0.001);
}

TEST_F(AwaitAtTheBoardsPace, ABoardThatFallsSilentEndsIt) {
  link_.silent_after = std::chrono::seconds(1);
  ASSERT_FALSE(AwaitBoardTime(0, {std::chrono::seconds(60), std::chrono::seconds(3)}));
  EXPECT_EQ(end_, WaitEnd::kSilent);
  // The last frame at 0.9 s, then 3 s of silence (to the 20 ms poll).
  EXPECT_NEAR(WallSeconds(), 3.9, 0.021);
}

TEST_F(AwaitAtTheBoardsPace, AHostsFramesToTheNodeAreNoSignOfItsLife) {
  link_.only_host_frames = true;
  ASSERT_FALSE(AwaitBoardTime(0, {std::chrono::seconds(60), std::chrono::seconds(3)}));
  EXPECT_EQ(end_, WaitEnd::kSilent);
  EXPECT_NEAR(WallSeconds(), 3.0, 0.021);
}

TEST_F(AwaitAtTheBoardsPace, ABoardWithoutHeartbeatsIsSilentOnceTheyStayAway) {
  // Its clock cannot be read, so only the absence of heartbeats can end the wait.
  link_.heartbeats = false;
  ASSERT_FALSE(AwaitBoardTime(0, {std::chrono::seconds(2), std::chrono::seconds(3)}));
  EXPECT_EQ(end_, WaitEnd::kSilent);
  EXPECT_NEAR(WallSeconds(), std::chrono::duration<double>(kHeartbeatSilence).count(),
              0.101);
  EXPECT_NE(why_.find("no heartbeat"), std::string::npos) << why_;
}

TEST_F(AwaitAtTheBoardsPace, ABoardInItsBootloaderIsNamedSoWithWhyItStays) {
  link_.bootloader = true;
  ASSERT_FALSE(AwaitBoardTime(0, {std::chrono::seconds(2), std::chrono::seconds(3)}));
  EXPECT_EQ(end_, WaitEnd::kSilent);
  EXPECT_NE(why_.find("node 1 is in its bootloader, ready (held by a host)"),
            std::string::npos)
      << why_;
  EXPECT_EQ(why_.find("HeartbeatHz"), std::string::npos) << why_;
}

TEST_F(AwaitAtTheBoardsPace, ABoardThatFallsSilentMidMotionIsNamedSo) {
  link_.silent_after = std::chrono::seconds(1);
  ASSERT_FALSE(AwaitBoardTime(0, {std::chrono::seconds(60), std::chrono::seconds(3)}));
  EXPECT_EQ(end_, WaitEnd::kSilent);
  EXPECT_NE(why_.find("node 1 is silent"), std::string::npos) << why_;
  EXPECT_NE(why_.find("its last heartbeat saying running"), std::string::npos) << why_;
  EXPECT_EQ(why_.find("HeartbeatHz"), std::string::npos) << why_;
}

TEST_F(AwaitAtTheBoardsPace, TheInterruptFlagEndsItAtOnce) {
  std::atomic<bool> interrupt{false};
  client_.SetInterrupt(&interrupt);
  int polls = 0;
  const bool done = client_.Await(
      [&] {
        if (++polls == 3) interrupt = true;
        return false;
      },
      {std::chrono::seconds(60), std::chrono::seconds(3)}, &end_, &why_);
  ASSERT_FALSE(done);
  EXPECT_EQ(end_, WaitEnd::kInterrupted);
  EXPECT_EQ(polls, 3);
}

// ---------------------------------------------------------------------------------
// Bus-off: the link counts the controller's bus-off error frames; the client tells its
// handler the moment one of its waits sees a new one.

class BusOffLink final : public CanLink {
 public:
  // The receives (counted from 1) during which an error frame reports bus-off.
  std::vector<int> bus_off_during;
  void ReportBusOff() {
    ++stats_.error_frames;
    ++stats_.bus_off;
  }

 private:
  bool DoSend(const protocol::CanFrame&, std::string*) override { return true; }
  ReceiveResult DoReceive(int, std::string*) override {
    ++receives_;
    if (std::find(bus_off_during.begin(), bus_off_during.end(), receives_) !=
        bus_off_during.end()) {
      ReportBusOff();
    }
    return {ReceiveStatus::kTimeout, {}};
  }
  bool DoSetFilters(std::span<const IdFilter>, std::string*) override { return true; }
  int receives_ = 0;
};

TEST(BoardClientBusOff, EachNewReportReachesTheHandlerOnce) {
  BusOffLink link;
  link.ReportBusOff();  // before the client: not this client's
  link.bus_off_during = {2, 4, 5};
  BoardClient client(&link, kNode);
  std::vector<std::uint64_t> told;
  client.OnBusOff([&](std::uint64_t total) { told.push_back(total); });
  std::string why;
  for (int i = 0; i < 6; ++i) ASSERT_TRUE(client.Poll(0, &why)) << why;
  EXPECT_EQ(told, (std::vector<std::uint64_t>{1, 2, 3}));
  EXPECT_EQ(client.bus_off(), 3u);
  EXPECT_EQ(link.stats().bus_off, 4u);
}

TEST(BoardClientBusOff, CountedWithoutAHandler) {
  BusOffLink link;
  link.bus_off_during = {1};
  BoardClient client(&link, kNode);
  std::string why;
  ASSERT_TRUE(client.Poll(0, &why)) << why;
  EXPECT_EQ(client.bus_off(), 1u);
}

// ---------------------------------------------------------------------------------
// Two boards with one node id: told apart by their BoardInfo instances and by their
// heartbeat clocks, against scripted frames; a restart is not a second board.

class TwoBoards : public ::testing::Test {
 protected:
  void Info(std::uint16_t instance) {
    protocol::BoardInfo info;
    info.build = 0x1958ba84;
    info.instance = instance;
    ASSERT_TRUE(board_->Send(protocol::Encode(info, kNode), &why_));
  }
  void Beat(std::uint32_t tick) {
    protocol::Heartbeat h;
    h.tick = tick;
    ASSERT_TRUE(board_->Send(protocol::Encode(h, kNode), &why_));
  }
  bool Ambiguous() {
    EXPECT_TRUE(client_.Poll(50, &why_)) << why_;
    return client_.ambiguous();
  }

  std::shared_ptr<InProcessBus> bus_ = InProcessBus::Create();
  std::unique_ptr<CanLink> board_ = bus_->Connect();
  std::unique_ptr<CanLink> host_ = bus_->Connect();
  BoardClient client_{host_.get(), kNode};
  std::string why_;
};

TEST_F(TwoBoards, OneBoardIsOneBoard) {
  Info(0x3f2a);
  for (std::uint32_t t = 50000; t < 70000; t += 1000) Beat(t);
  Info(0x3f2a);
  Beat(70000);
  EXPECT_FALSE(Ambiguous());
  ASSERT_TRUE(client_.info());
  EXPECT_EQ(client_.info()->instance, 0x3f2a);
  EXPECT_EQ(client_.info()->build, 0x1958ba84u);
  EXPECT_EQ(client_.AmbiguityMessage(), "");
}

TEST_F(TwoBoards, TwoInstancesWhileNeitherRestartedAreTwoBoards) {
  // Started together: their clocks agree, only their BoardInfo tells them apart. The
  // first BoardInfo of the second is a sign (a motion stops); its second, the proof.
  Info(0x3f2a);
  Beat(50000);
  Info(0x9b01);
  Beat(50010);
  EXPECT_TRUE(Ambiguous());
  Info(0x3f2a);
  Beat(51000);
  Info(0x9b01);
  Beat(51010);
  EXPECT_TRUE(Ambiguous());
  EXPECT_EQ(client_.AmbiguityMessage(),
            "node 1 is answered by two boards (instances 3f2a and 9b01): give each its "
            "own node id");
  // Every wait ends at once, saying so.
  WaitEnd end{};
  EXPECT_FALSE(client_.Await([] { return true; }, {}, &end, &why_));
  EXPECT_EQ(end, WaitEnd::kAmbiguous);
  EXPECT_EQ(why_, client_.AmbiguityMessage());
}

TEST_F(TwoBoards, OneStrayBoardInfoIsASignNotAProof) {
  // A frame of a flooded bus that decodes as a BoardInfo of another instance, amid one
  // board's steady heartbeats: every wait ends at once (a motion stops on the first
  // sign), and the message says what was seen, not that there are two boards.
  Info(0x3f2a);
  for (std::uint32_t t = 50000; t < 53000; t += 1000) Beat(t);
  Info(0x3f2a);
  Beat(53000);
  Info(0x77c5);
  Beat(54000);
  Beat(55000);
  EXPECT_TRUE(Ambiguous());
  EXPECT_EQ(client_.AmbiguityMessage(),
            "node 1 showed a sign of a second board on its node id (a BoardInfo of "
            "instance 77c5 amid 3f2a's): seen once, which a stray or corrupted frame can "
            "also cause (mjc list shows every board on the bus)");
  WaitEnd end{};
  EXPECT_FALSE(client_.Await([] { return true; }, {}, &end, &why_));
  EXPECT_EQ(end, WaitEnd::kAmbiguous);
  EXPECT_EQ(why_, client_.AmbiguityMessage());
}

TEST_F(TwoBoards, ARestartIntoANewInstanceIsNotASecondBoard) {
  // A simulated board draws a new instance at every start; its clock starts anew.
  Info(0x3f2a);
  Beat(50000);
  Beat(51000);
  Info(0x9b01);
  Beat(0);
  Beat(1000);
  EXPECT_FALSE(Ambiguous());
  EXPECT_EQ(client_.info()->instance, 0x9b01);
  // ...unless the old one speaks again: a sign, named as such.
  Info(0x3f2a);
  EXPECT_TRUE(Ambiguous());
  EXPECT_EQ(client_.AmbiguityMessage(),
            "node 1 showed a sign of a second board on its node id (a BoardInfo of "
            "instance 3f2a amid 9b01's): seen once, which a stray or corrupted frame can "
            "also cause (mjc list shows every board on the bus)");
  // Heard again from both: two boards.
  Beat(2000);
  Info(0x9b01);
  EXPECT_TRUE(Ambiguous());
  EXPECT_EQ(client_.AmbiguityMessage(),
            "node 1 is answered by two boards (instances 3f2a and 9b01): give each its "
            "own node id");
}

TEST_F(TwoBoards, InterleavedClocksWithoutBoardInfoAreTwoBoards) {
  // An older image sends no BoardInfo: one step back is a restart, two are two boards.
  Beat(50000);
  Beat(100);
  Beat(1100);
  EXPECT_FALSE(Ambiguous());
  Beat(51000);
  Beat(2100);
  EXPECT_TRUE(Ambiguous());
  EXPECT_EQ(client_.AmbiguityMessage(),
            "node 1 is answered by two boards (their heartbeat clocks interleave): give "
            "each its own node id");
}

TEST_F(TwoBoards, IdentifyTellsThemApartBeforeTheirClocksSeemToHaveRun) {
  // The younger board heard first: the older one's clock is 25 s ahead, a jump that
  // must not count as the node's time having run (it would end the wait unjudged).
  for (std::uint32_t t = 0; t < 3000; t += 1000) {
    Beat(50000 + t);
    Beat(300000 + t);
  }
  WaitEnd end{};
  EXPECT_FALSE(client_.Identify(&end, &why_));
  EXPECT_EQ(end, WaitEnd::kAmbiguous);
  EXPECT_EQ(client_.AmbiguityMessage(),
            "node 1 is answered by two boards (their heartbeat clocks interleave): give "
            "each its own node id");
}

TEST_F(TwoBoards, IdentifyOfOneBoardEndsOnceItsClockRanAPeriodAndATenth) {
  Info(0x3f2a);
  for (std::uint32_t t = 300000; t <= 311000; t += 1000) Beat(t);
  WaitEnd end{};
  EXPECT_TRUE(client_.Identify(&end, &why_)) << why_;
  EXPECT_EQ(client_.info()->instance, 0x3f2a);
}

TEST_F(TwoBoards, AnotherNodesBoardsAreNotThisOnes) {
  protocol::BoardInfo info;
  info.instance = 0x1111;
  ASSERT_TRUE(board_->Send(protocol::Encode(info, kNode + 1), &why_));
  Info(0x3f2a);
  Beat(1000);
  EXPECT_FALSE(Ambiguous());
  EXPECT_EQ(client_.instances(), (std::vector<std::uint16_t>{0x3f2a}));
}

TEST_F(AwaitAtTheBoardsPace, IdentifyListensABoardInfoPeriodOfTheBoardsOwnTime) {
  // A board at a hundredth of real time, a heartbeat every 100 ms of its time: 110 ms
  // of its time end at its third heartbeat (200 ms), 20 s of this machine's.
  link_.board_rate = 0.01;
  ASSERT_TRUE(client_.Identify(&end_, &why_)) << why_;
  EXPECT_NEAR(WallSeconds(), 20.0, 0.01);
  EXPECT_FALSE(client_.info());  // this scripted board sends none
}

TEST_F(AwaitAtTheBoardsPace, IdentifyOfASilentNodeSaysSoInTheOneWording) {
  link_.silent_after = std::chrono::seconds(0);
  ASSERT_FALSE(client_.Identify(&end_, &why_));
  EXPECT_EQ(end_, WaitEnd::kSilent);
  EXPECT_EQ(why_,
            "node 1 is silent (is the board powered and on the in-process bus? try mjc "
            "list)");
}

}  // namespace
