// A trial over the protocol without a kernel: the simulated board (app + CAN node on
// the plant) in one thread, the host's BoardClient in another, joined by an in-process
// bus. Every window reaches the host through its five frames, and the host-received
// energies match the plant's ground truth over the same ticks.
//
// The same trial under a full-rate frame flood: besides the host's own traffic, the
// board's CAN node receives two more frames every 100 µs tick (20,000 frames/s, about
// what CAN FD at 1/5 Mbit/s carries with 8-byte payloads) — other boards' telemetry,
// commands for other nodes, malformed frames for this node, parameter reads that each
// need a reply, and random identifiers and lengths. The trial must complete with every
// window, its energies as close to the plant's truth as without the flood, no fault,
// and every received frame accounted for by the node's counters.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdio>
#include <mutex>
#include <numbers>
#include <random>
#include <thread>
#include <vector>

#include "mjc/app/can_node.h"
#include "mjc/host/report.h"
#include "mjc/host/trial_runner.h"
#include "mjc/plant/params.h"
#include "mjc/sim/link_can_port.h"
#include "mjc/sim/scenarios.h"

namespace {

using namespace mjc;
using namespace mjc::protocol;

// The flood's frames, in a fixed rotation so every kind is equally represented.
class Flood {
 public:
  explicit Flood(std::uint8_t node) : node_(node) {}

  CanFrame Next() {
    const std::uint8_t other = static_cast<std::uint8_t>(2 + (n_ % 7));  // nodes 2..8
    CanFrame f;
    switch (n_++ % 6) {
      case 0:  // another board's telemetry
        f = Encode(TelemetryAngles{Angle::FromRaw(static_cast<std::int32_t>(rng_())),
                                   Angle::FromRaw(static_cast<std::int32_t>(rng_()))},
                   other);
        break;
      case 1:  // the host commanding another node
        f = Encode(Command{CommandCode::kStop, static_cast<std::uint8_t>(n_)}, other);
        break;
      case 2:  // a truncated setpoint for this node
        f = Encode(Setpoint{Angle::FromRaw(0), 0}, node_);
        f.length = 3;
        ++malformed_sent_;
        break;
      case 3:  // a parameter read for this node: every one needs a reply
        f = Encode(ParamRead{ParamId::kTelemetryAnglesHz}, node_);
        ++param_reads_sent_;
        break;
      case 4:  // an unused function code for this node
        f.id = MakeId(0x7F, node_);
        f.length = 8;
        break;
      default: {  // anything for another node: a random identifier, length, payload
        do {
          f.id = static_cast<std::uint32_t>(rng_()) & 0x7FFu;
        } while (NodeOf(f.id) == node_);
        f.length = static_cast<std::uint8_t>(rng_() % 9);
        for (auto& b : f.data) b = static_cast<std::uint8_t>(rng_());
        break;
      }
    }
    return f;
  }
  std::uint32_t malformed_sent() const { return malformed_sent_; }
  std::uint32_t param_reads_sent() const { return param_reads_sent_; }

 private:
  std::uint8_t node_;
  std::uint32_t n_ = 0;
  std::uint32_t malformed_sent_ = 0;
  std::uint32_t param_reads_sent_ = 0;
  std::mt19937 rng_{20261121};
};

// What one board-side run saw, besides the trial the host assembled.
struct BoardRun {
  host::BoardTrial trial;
  std::vector<double> truth_energy;  // the plant's interface energy, index: board tick
  app::CanNodeCounters counters;
  std::uint32_t ticks = 0;
  std::uint32_t tick_gaps = 0;  // ticks whose counter did not advance by exactly one
  std::uint32_t from_host = 0;
  std::uint32_t flooded = 0;
  std::uint32_t param_replies = 0;
  int progress_lines = 0;            // the host's per-window progress callbacks
  std::uint64_t host_malformed = 0;  // frames the host could not decode
  bool faulted = false;
};

// The board's port on the in-process bus, counting what passes: the host's frames in,
// the parameter replies out.
class CountingPort final : public hal::CanPort {
 public:
  explicit CountingPort(host::CanLink* link) : port_(link) {}
  std::uint32_t received = 0;
  std::uint32_t param_replies = 0;

 private:
  bool DoSend(const CanFrame& f) override {
    if (FunctionOf(f.id) == static_cast<std::uint8_t>(Function::kParamValue)) {
      ++param_replies;
    }
    return port_.Send(f);
  }
  bool DoReceive(CanFrame* f) override {
    if (!port_.Receive(f)) return false;
    ++received;
    return true;
  }
  std::uint32_t DoTakeBusOff() override { return port_.TakeBusOff(); }
  hal::CanPortCounters DoCounters() const override { return port_.counters(); }
  sim::LinkCanPort port_;
};

// Five 15° repetitions at 0.5 Hz on subject 1's hand, calibrated with the plant's own
// slack; `flood` (may be null) adds `per_tick` frames before every tick.
BoardRun RunTrial(Flood* flood, int per_tick) {
  auto bus = host::InProcessBus::Create();
  auto board_link = bus->Connect();
  auto host_link = bus->Connect();

  plant::PlantParams params = plant::LoadPlantParams("default");
  params.interface = plant::LoadPlantParams("subject1").interface;
  CountingPort port(board_link.get());
  sim::SimBoard board(params, app::JointBoardConfig{app::DefaultJointConfig(), {}, 0, 1},
                      &port);
  Calibration cal;
  cal.backlash.c_right = Angle::Quantize(params.cable.c_right_rad);
  cal.backlash.c_left = Angle::Quantize(params.cable.c_left_rad);
  board.app().SetCalibration(cal);
  board.Tick();
  app::CanNode& node = board.board().node();

  BoardRun run;
  std::mutex truth_mutex;
  std::atomic<bool> stop{false};
  std::thread board_thread([&] {
    std::uint32_t last_tick = board.app().last().telemetry.tick;
    while (!stop) {
      for (int i = 0; flood != nullptr && i < per_tick; ++i) {
        node.HandleFrame(flood->Next());
        ++run.flooded;
      }
      {
        std::lock_guard lock(truth_mutex);
        const std::uint32_t tick = board.app().last().telemetry.tick + 1;
        if (run.truth_energy.size() <= tick) run.truth_energy.resize(tick + 1, 0.0);
        run.truth_energy[tick] = board.plant().truth().interface_energy_J;
      }
      board.Tick();
      ++run.ticks;
      const std::uint32_t tick = board.app().last().telemetry.tick;
      if (tick != last_tick + 1) ++run.tick_gaps;
      last_tick = tick;
      run.faulted = run.faulted || board.app().state() == app::BoardState::kFault;
      board.Poll();
    }
  });

  host::BoardClient client(host_link.get(), 1);
  TrialConfig config;
  config.amplitude = Angle::Quantize(15.0 * std::numbers::pi / 180.0);
  config.frequency_mHz = 500;
  config.repetitions = 5;
  config.rest_100ms = 5;
  run.trial = host::RunBoardTrial(
      client, config, [&](const host::BoardWindow&) { ++run.progress_lines; });
  stop = true;
  board_thread.join();
  run.from_host = port.received;
  run.param_replies = port.param_replies;
  run.host_malformed = client.malformed();
  run.counters = node.counters();
  return run;
}

// The middle three flexions against the plant's truth over the same ticks.
void ExpectWindowsMatchTruth(const BoardRun& run) {
  const auto flexions = host::AnalysedFlexions(run.trial.windows, 5);
  ASSERT_EQ(flexions.size(), 3u);
  for (const host::BoardWindow* analysed : flexions) {
    const host::BoardWindow& w = *analysed;
    ASSERT_LT(w.end_tick, run.truth_energy.size());
    const double load = run.truth_energy[w.peak_tick] - run.truth_energy[w.start_tick];
    const double unload = run.truth_energy[w.end_tick] - run.truth_energy[w.peak_tick];
    EXPECT_NEAR(w.loading_J, load, 0.02 * load) << "repetition " << w.repetition;
    EXPECT_NEAR(w.unloading_J, unload, 0.02 * load) << "repetition " << w.repetition;
    EXPECT_TRUE(w.eta_valid);
    EXPECT_NEAR(w.eta_percent, (1 - std::fabs(unload) / load) * 100, 1.0);
  }
}

TEST(BusTrial, WindowsArriveAndMatchPlantTruth) {
  const BoardRun run = RunTrial(nullptr, 0);
  ASSERT_TRUE(run.trial.completed) << run.trial.error;
  EXPECT_EQ(run.trial.windows.size(), 10u);  // five flexions, five extensions
  EXPECT_EQ(run.progress_lines, 10);
  EXPECT_EQ(run.host_malformed, 0u);
  EXPECT_FALSE(run.faulted);
  ExpectWindowsMatchTruth(run);
}

TEST(BusTrial, FullRateFloodKeepsEveryWindowAndCountsEveryFrame) {
  constexpr int kPerTick = 2;
  Flood flood(1);
  const BoardRun run = RunTrial(&flood, kPerTick);
  ASSERT_TRUE(run.trial.completed) << run.trial.error;
  EXPECT_EQ(run.trial.windows.size(), 10u);
  EXPECT_FALSE(run.faulted);
  EXPECT_EQ(run.tick_gaps, 0u);
  // The flood really was full rate for the whole trial.
  EXPECT_EQ(run.flooded, kPerTick * run.ticks);
  EXPECT_GT(run.flooded, 2u * 5 * 20000);  // five 2 s cycles at 20,000 frames/s at least

  // Every received frame accounted for, each kind where it belongs.
  const app::CanNodeCounters& c = run.counters;
  EXPECT_EQ(c.received(), run.from_host + run.flooded);
  // The truncated setpoints, and nothing else (the host sends no malformed frames).
  EXPECT_EQ(c.malformed[static_cast<int>(DecodeError::kWrongLength)],
            flood.malformed_sent());
  EXPECT_EQ(c.tx_dropped, 0u);
  EXPECT_EQ(c.events_dropped, 0u);
  // Every parameter read answered (the flood's, and the host's own few).
  EXPECT_GE(run.param_replies, flood.param_reads_sent());
  std::printf(
      "flood: %u ticks, %u flood + %u host frames received, %u malformed, "
      "%u ignored, %u parameter replies, %u dropped\n",
      run.ticks, run.flooded, run.from_host,
      c.malformed[static_cast<int>(DecodeError::kWrongLength)], c.ignored,
      run.param_replies, c.tx_dropped + c.events_dropped);
  ExpectWindowsMatchTruth(run);
}

}  // namespace
