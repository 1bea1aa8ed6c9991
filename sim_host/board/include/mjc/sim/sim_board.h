// The simulated joint board: the unmodified firmware application (JointApp and its
// ControlTick) on SimJointIo, bound to a plant, stepped at the board's tick rate in
// simulated time. Each tick: the app samples the plant's sensors, runs its tick and
// writes the bridge; the plant then integrates one tick period under that actuation.
#pragma once

#include <cstdint>
#include <memory>

#include "hal/sim/sim_joint_io.h"
#include "mjc/app/joint_app.h"
#include "mjc/plant/plant.h"

namespace mjc::sim {

class SimBoard {
 public:
  SimBoard(const plant::PlantParams& params, const ControlConfig& config);

  // One control tick of simulated time.
  void Tick();

  app::JointApp& app() { return *app_; }
  plant::Plant& plant() { return *plant_; }
  hal::SimJointIo& io() { return *io_; }
  double tick_period_s() const { return period_s_; }
  std::uint32_t tick_hz() const { return tick_hz_; }

 private:
  std::uint32_t tick_hz_;
  double period_s_;
  std::unique_ptr<plant::Plant> plant_;
  std::unique_ptr<hal::SimJointIo> io_;
  // The app is ~20 KB (delay lines, queues): on the heap of the host process, as the
  // firmware keeps it in static RAM.
  std::unique_ptr<app::JointApp> app_;
};

}  // namespace mjc::sim
