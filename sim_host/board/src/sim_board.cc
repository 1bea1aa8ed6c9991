#include "mjc/sim/sim_board.h"

namespace mjc::sim {

SimBoard::SimBoard(const plant::PlantParams& params, const ControlConfig& config)
    : tick_hz_(config.tick_hz),
      period_s_(1.0 / config.tick_hz),
      plant_(std::make_unique<plant::Plant>(params)),
      io_(std::make_unique<hal::SimJointIo>(plant_.get())),
      app_(std::make_unique<app::JointApp>(config)) {}

void SimBoard::Tick() {
  app_->ISR_Tick(*io_);
  plant_->Step(io_->duty(), io_->bridge_enabled(), period_s_);
}

}  // namespace mjc::sim
