#include "mjc/sim/sim_board.h"

namespace mjc::sim {

SimBoard::SimBoard(const plant::PlantParams& params, const app::JointBoardConfig& config,
                   hal::CanPort* port, hal::Flash* flash)
    : tick_hz_(config.control.tick_hz),
      period_s_(1.0 / config.control.tick_hz),
      plant_(std::make_unique<plant::Plant>(params)),
      io_(std::make_unique<hal::SimJointIo>(plant_.get())),
      board_(std::make_unique<app::JointBoard>(config, port, flash)) {}

void SimBoard::Tick() {
  board_->ISR_Tick(*io_);
  plant_->Step(io_->duty(), io_->bridge_enabled(), period_s_);
}

}  // namespace mjc::sim
