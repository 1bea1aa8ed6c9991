// A trial over the protocol without a kernel: the simulated board (app + CAN node on
// the plant) in one thread, the host's BoardClient in another, joined by an in-process
// bus. Every window reaches the host through its five frames, and the host-received
// energies match the plant's ground truth over the same ticks.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <mutex>
#include <thread>
#include <vector>

#include "mjc/app/can_node.h"
#include "mjc/host/trial_runner.h"
#include "mjc/plant/params.h"
#include "mjc/sim/scenarios.h"

namespace {

using namespace mjc;

TEST(BusTrial, WindowsArriveAndMatchPlantTruth) {
  auto bus = host::InProcessBus::Create();
  auto board_link = bus->Connect();
  auto host_link = bus->Connect();

  plant::PlantParams params = plant::LoadPlantParams("default");
  params.integration.max_step_s = 33.4e-6;
  params.interface = plant::LoadPlantParams("subject1").interface;
  sim::SimBoard board(params, sim::DefaultBoardConfig());
  Calibration cal;
  cal.backlash.c_right = Angle::Quantize(params.cable.c_right_rad);
  cal.backlash.c_left = Angle::Quantize(params.cable.c_left_rad);
  board.app().SetCalibration(cal);
  board.Tick();
  app::CanNode node(&board.app(), app::CanNodeConfig{});

  // The board thread records the plant's interface energy at each board tick.
  std::mutex truth_mutex;
  std::vector<double> truth_energy;  // index: board tick
  std::atomic<bool> stop{false};
  std::thread board_thread([&] {
    std::string why;
    while (!stop) {
      while (auto f = board_link->Receive(0)) node.HandleFrame(f->frame);
      {
        std::lock_guard lock(truth_mutex);
        const std::uint32_t tick = board.app().last().telemetry.tick + 1;
        if (truth_energy.size() <= tick) truth_energy.resize(tick + 1, 0.0);
        truth_energy[tick] = board.plant().truth().interface_energy_J;
      }
      board.Tick();
      node.Poll();
      protocol::CanFrame out;
      while (node.PopTx(&out)) board_link->Send(out, &why);
    }
  });

  host::BoardClient client(host_link.get(), 1);
  protocol::TrialConfig config;
  config.amplitude = Angle::Quantize(15.0 * 3.14159265358979323846 / 180.0);
  config.frequency_mHz = 500;
  config.repetitions = 5;
  config.rest_100ms = 5;
  int progress_lines = 0;
  const host::BoardTrial trial = host::RunBoardTrial(
      client, config, [&](const host::BoardWindow&) { ++progress_lines; }, 120.0);
  stop = true;
  board_thread.join();

  ASSERT_TRUE(trial.completed) << trial.error;
  EXPECT_EQ(trial.windows.size(), 10u);  // five flexions, five extensions
  EXPECT_EQ(progress_lines, 10);
  EXPECT_EQ(client.malformed(), 0u);
  const auto flexions = host::MiddleFlexions(trial.windows, 5);
  ASSERT_EQ(flexions.size(), 3u);
  for (const host::BoardWindow& w : flexions) {
    ASSERT_LT(w.end_tick, truth_energy.size());
    const double load = truth_energy[w.peak_tick] - truth_energy[w.start_tick];
    const double unload = truth_energy[w.end_tick] - truth_energy[w.peak_tick];
    EXPECT_NEAR(w.loading_J, load, 0.02 * load) << "repetition " << w.repetition;
    EXPECT_NEAR(w.unloading_J, unload, 0.02 * load) << "repetition " << w.repetition;
    EXPECT_TRUE(w.eta_valid);
    EXPECT_NEAR(w.eta_percent, (1 - std::fabs(unload) / load) * 100, 1.0);
  }
}

}  // namespace
