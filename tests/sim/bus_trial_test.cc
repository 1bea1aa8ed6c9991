// A trial over the protocol without a kernel: the simulated board (app + CAN node on
// the plant) and the host's BoardClient, joined by the in-process bus of
// sim_host/bus (sim::BusBoard, lock-stepped: the paper's scenarios run on it). Every
// window reaches the host through its five frames, and the host-received energies match
// the plant's ground truth over the same ticks.
//
// The same trial under a full-rate frame flood: besides the host's own traffic, the
// board's CAN node receives two more frames every 100 µs tick (20,000 frames/s, about
// what CAN FD at 1/5 Mbit/s carries with 8-byte payloads) — other boards' telemetry,
// commands for other nodes, malformed frames for this node, parameter reads that each
// need a reply, and random identifiers and lengths. The trial must complete with every
// window, its energies as close to the plant's truth as without the flood, no fault,
// and every received frame accounted for by the node's counters.
// The rig (board, host, flood) is tests/sim/bus_trial_rig.h; ./bench's sim_flood_*
// figures come from the same run (tests/bench/sim_flood.cc).
#include <gtest/gtest.h>

#include <cmath>

#include "bus_trial_rig.h"
#include "mjc/app/joint_config.h"
#include "mjc/host/calibration_io.h"
#include "mjc/host/report.h"
#include "mjc/plant/params.h"
#include "mjc/sim/bus_board.h"

namespace {

using namespace mjc;
using namespace mjc::protocol;
using namespace mjc::bus_trial;

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
  ExpectWindowsMatchTruth(run);
}

// The bus is lock-stepped: the same trial twice gives the same windows bit for bit
// (the same ticks, the same energies), whatever this machine did meanwhile.
TEST(BusBoard, RunsAreTheSameBitForBit) {
  const BoardRun a = RunTrial(nullptr, 0);
  const BoardRun b = RunTrial(nullptr, 0);
  ASSERT_TRUE(a.trial.completed && b.trial.completed);
  ASSERT_EQ(a.trial.windows.size(), b.trial.windows.size());
  for (std::size_t i = 0; i < a.trial.windows.size(); ++i) {
    const host::BoardWindow &x = a.trial.windows[i], &y = b.trial.windows[i];
    EXPECT_EQ(x.start_tick, y.start_tick);
    EXPECT_EQ(x.end_tick, y.end_tick);
    EXPECT_EQ(x.loading_J, y.loading_J);
    EXPECT_EQ(x.unloading_J, y.unloading_J);
    EXPECT_EQ(x.stiffness_Nm_rad, y.stiffness_Nm_rad);
  }
  EXPECT_EQ(a.ticks, b.ticks);
  EXPECT_EQ(a.truth_energy, b.truth_energy);
}

// The board runs only while the host waits for it, and by no more than the wait's
// length of its own time.
TEST(BusBoard, RunsOnlyWhileTheHostWaits) {
  sim::BusBoard bus(plant::LoadPlantParams("default"), app::DefaultJointConfig());
  host::BoardClient& client = bus.client();
  std::string why;
  ASSERT_TRUE(client.Send(ParamRead{ParamId::kTelemetryAnglesHz}, &why)) << why;
  EXPECT_EQ(bus.ticks(), 0u);
  ASSERT_TRUE(client.Poll(20, &why)) << why;
  EXPECT_GT(bus.ticks(), 0u);
  EXPECT_LE(bus.ticks(), 200u);  // 20 ms at 10 kHz
  const std::uint64_t before = bus.ticks();
  const auto rate = client.ReadParam(ParamId::kTelemetryAnglesHz, 500, &why);
  ASSERT_TRUE(rate) << why;
  EXPECT_EQ(*rate, TelemetryRates{}.angles_hz);
  EXPECT_LE(bus.ticks() - before, 5000u);  // within the read's 500 ms
}

// mjc calibrate's upload without the kernel's ISO-TP: segmented on a link of the bus,
// answered by the board's own receiver, and held (read back as the tool does); a
// record the board's checks refuse is answered with why and changes nothing.
TEST(BusBoard, CalibrationUploadIsAnsweredAndHeld) {
  sim::BusBoard bus(plant::LoadPlantParams("default"), app::DefaultJointConfig());
  host::BoardClient& client = bus.client();
  const auto isotp = bus.Connect();
  std::string why;

  CalibrationRecord bad;
  bad.backlash.c_right = Angle::Quantize(-0.02);  // c_r below c_l: no play operator
  bad.backlash.c_left = Angle::Quantize(0.02);
  const host::UploadOutcome refused =
      host::UploadCalibration(client, *isotp, bad, 1000, &why);
  ASSERT_EQ(refused.status, host::UploadStatus::kAnswered) << why;
  EXPECT_EQ(refused.result, CalibrationResult::kOutOfRange);
  auto held = host::ReadCalibration(client, &why);
  ASSERT_TRUE(held) << why;
  EXPECT_FALSE(held->calibrated);

  CalibrationRecord good;
  good.backlash.c_right = Angle::Quantize(0.019);
  good.backlash.c_left = Angle::Quantize(-0.016);
  good.joint_zero_count = 42;
  const host::UploadOutcome sent =
      host::UploadCalibration(client, *isotp, good, 1000, &why);
  ASSERT_EQ(sent.status, host::UploadStatus::kAnswered) << why;
  EXPECT_EQ(sent.result, CalibrationResult::kAccepted);
  held = host::ReadCalibration(client, &why);
  ASSERT_TRUE(held) << why;
  EXPECT_TRUE(held->calibrated);
  EXPECT_EQ(held->record.backlash.c_right, good.backlash.c_right);
  EXPECT_EQ(held->record.backlash.c_left, good.backlash.c_left);
  EXPECT_EQ(held->record.joint_zero_count, 42);
  EXPECT_TRUE(bus.app().calibrated());  // the board's side agrees
}

// Drops the ISO-TP consecutive frame of sequence number 3 of the first `transfers`
// transfers it carries: the board's reassembly fails (out of sequence).
class BreakingLink final : public host::CanLink {
 public:
  BreakingLink(host::CanLink* link, int transfers) : link_(link), left_(transfers) {}

 private:
  bool DoSend(const protocol::CanFrame& f, std::string* why) override {
    if ((f.data[0] >> 4) == 1) broken_ = false;  // a first frame: a new transfer
    if (!broken_ && left_ > 0 && f.data[0] == 0x23) {
      broken_ = true;
      --left_;
      return true;  // lost
    }
    return link_->Send(f, why);
  }
  host::ReceiveResult DoReceive(int timeout_ms, std::string* why) override {
    return link_->Receive(timeout_ms, why);
  }
  bool DoSetFilters(std::span<const host::IdFilter> filters, std::string* why) override {
    return link_->SetFilters(filters, why);
  }
  host::CanLink* link_;
  int left_;
  bool broken_ = false;
};

TEST(BusBoard, ACalibrationTransferTheBoardLostIsSentAgain) {
  sim::BusBoard bus(plant::LoadPlantParams("default"), app::DefaultJointConfig());
  host::BoardClient& client = bus.client();
  const auto isotp = bus.Connect();
  CalibrationRecord good;
  good.backlash.c_right = Angle::Quantize(0.019);
  good.backlash.c_left = Angle::Quantize(-0.016);
  std::string why;
  // Two transfers broken: the board says so each time, the third is accepted.
  BreakingLink twice(isotp.get(), 2);
  const host::UploadOutcome sent =
      host::UploadCalibration(client, twice, good, 1000, &why);
  ASSERT_EQ(sent.status, host::UploadStatus::kAnswered) << why;
  EXPECT_EQ(sent.result, CalibrationResult::kAccepted);
  EXPECT_EQ(sent.transfers, 3);
  EXPECT_TRUE(bus.app().calibrated());
  // Every transfer broken: the board's answer after the last retry.
  BreakingLink always(isotp.get(), 100);
  const host::UploadOutcome lost =
      host::UploadCalibration(client, always, good, 1000, &why);
  ASSERT_EQ(lost.status, host::UploadStatus::kAnswered) << why;
  EXPECT_EQ(lost.result, CalibrationResult::kReassemblyError);
  EXPECT_EQ(lost.transfers, host::kMostReassemblyRetries + 1);
}

}  // namespace
