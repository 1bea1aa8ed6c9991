// The simulated joint board: the firmware's JointBoard (application, CAN node,
// calibration store) on SimJointIo, bound to a plant, stepped at the board's tick rate
// in simulated time. Each tick: the board samples the plant's sensors, runs its tick
// and writes the bridge; the plant then integrates one tick period under that
// actuation. The main loop's pass (Poll) is the caller's to run, as often as a board's
// main loop would.
#pragma once

#include <cstdint>
#include <memory>

#include "hal/sim/sim_joint_io.h"
#include "mjc/app/joint_board.h"
#include "mjc/plant/plant.h"

namespace mjc::sim {

class SimBoard {
 public:
  // `port` and `flash` as for JointBoard: null for a board without a bus (rigs that
  // drive the app directly; the paper's scenarios go through sim::BusBoard) or without
  // persistence.
  SimBoard(const plant::PlantParams& params, const app::JointBoardConfig& config,
           hal::CanPort* port = nullptr, hal::Flash* flash = nullptr);
  SimBoard(const plant::PlantParams& params, const ControlConfig& config)
      : SimBoard(params, app::JointBoardConfig{config, {}, 0, 1}) {}

  // One control tick of simulated time.
  void Tick();
  // The main loop's pass (JointBoard::Poll).
  void Poll() { board_->Poll(); }

  app::JointBoard& board() { return *board_; }
  app::JointApp& app() { return board_->app(); }
  plant::Plant& plant() { return *plant_; }
  hal::SimJointIo& io() { return *io_; }
  double tick_period_s() const { return period_s_; }
  std::uint32_t tick_hz() const { return tick_hz_; }

 private:
  std::uint32_t tick_hz_;
  double period_s_;
  std::unique_ptr<plant::Plant> plant_;
  std::unique_ptr<hal::SimJointIo> io_;
  // The board is ~20 KB (delay lines, queues): on the heap of the host process, as the
  // firmware keeps it in static RAM.
  std::unique_ptr<app::JointBoard> board_;
};

}  // namespace mjc::sim
