#include "virtual_board_rig.h"

#include <algorithm>
#include <cmath>

#include "mjc/host/calibration_io.h"
#include "mjc/host/report.h"
#include "mjc/host/units.h"

namespace mjc::g474board::rig {

using namespace mjc::protocol;

EnergyTruth::EnergyTruth(VirtualBoard& board) {
  board.SetStepObserver([this](const plant::Plant& plant, std::uint32_t tick) {
    std::lock_guard lock(mutex_);
    if (energy_J_.size() <= tick) energy_J_.resize(tick + 1, 0.0);
    energy_J_[tick] = plant.interface_energy_J();
  });
}

std::optional<double> EnergyTruth::At(std::uint32_t tick) const {
  std::lock_guard lock(mutex_);
  if (tick >= energy_J_.size()) return std::nullopt;
  return energy_J_[tick];
}

protocol::SweepConfig PaperSweep() {
  protocol::SweepConfig sweep;
  sweep.end_amplitude = Angle::Quantize(host::DegToRad(30));
  sweep.frequency_mHz = 500;
  sweep.repetitions = 10;
  sweep.rest_100ms = 5;
  return sweep;
}

protocol::TrialConfig JudgedTrial() {
  protocol::TrialConfig trial;
  trial.amplitude = Angle::Quantize(host::DegToRad(15));
  trial.frequency_mHz = 500;
  trial.repetitions = 5;
  trial.rest_100ms = 5;
  return trial;
}

double CalibrationRun::worst_error_deg() const {
  return std::max(std::fabs(error_right_deg), std::fabs(error_left_deg));
}

CalibrationRun SweepAndFit(host::BoardClient& client, const protocol::SweepConfig& sweep,
                           const plant::PlantParams& plant) {
  CalibrationRun run;
  // Fitted and made into the record as `mjc calibrate` does (no robot description).
  host::SweepRun swept = host::RunSweep(client, sweep, nullptr, false);
  run.samples = swept.samples.motor_rad.size();
  if (swept.fitted) run.fit = swept.fitted->fit;
  if (!swept.error.empty()) {
    run.error = swept.error;
    return run;
  }
  run.record = *swept.fitted->record;
  run.error_right_deg = host::RadToDeg(run.fit.c_right_rad - plant.cable.c_right_rad);
  run.error_left_deg = host::RadToDeg(run.fit.c_left_rad - plant.cable.c_left_rad);
  return run;
}

double WindowError::energy_error_pct() const {
  return 100.0 *
         std::max(std::fabs(loading_J - truth_loading_J),
                  std::fabs(unloading_J - truth_unloading_J)) /
         std::fabs(truth_loading_J);
}

double WindowError::eta_error_pt() const { return std::fabs(eta_pct - truth_eta_pct); }

double TrialRun::worst_energy_error_pct() const {
  double worst = 0;
  for (const WindowError& w : flexions) worst = std::max(worst, w.energy_error_pct());
  return worst;
}

double TrialRun::worst_eta_error_pt() const {
  double worst = 0;
  for (const WindowError& w : flexions) worst = std::max(worst, w.eta_error_pt());
  return worst;
}

TrialRun RunTrialAgainstTruth(host::BoardClient& client, const EnergyTruth& truth,
                              const protocol::TrialConfig& config) {
  TrialRun run;
  run.trial = host::RunBoardTrial(client, config, [](const host::BoardWindow&) {});
  if (!run.trial.completed) {
    run.error = "the trial did not complete: " + run.trial.error;
    return run;
  }
  const auto flexions = host::AnalysedFlexions(run.trial.windows, config.repetitions);
  if (flexions.size() != 3) {
    run.error =
        "the trial has " + std::to_string(flexions.size()) + " analysed flexions, not 3";
    return run;
  }
  for (const host::BoardWindow* flexion : flexions) {
    const host::BoardWindow& w = *flexion;
    const auto start = truth.At(w.start_tick), peak = truth.At(w.peak_tick),
               end = truth.At(w.end_tick);
    if (!start || !peak || !end) {
      run.error = "repetition " + std::to_string(w.repetition) +
                  ": its ticks were not recorded (a reset?)";
      return run;
    }
    WindowError e;
    e.repetition = w.repetition;
    e.loading_J = w.loading_J;
    e.unloading_J = w.unloading_J;
    e.eta_pct = w.eta_percent;
    e.truth_loading_J = *peak - *start;
    e.truth_unloading_J = *end - *peak;
    e.truth_eta_pct = (1 - std::fabs(e.truth_unloading_J) / e.truth_loading_J) * 100;
    run.flexions.push_back(e);
    if (!w.eta_valid) run.error = "the board formed no η in an analysed flexion";
  }
  return run;
}

}  // namespace mjc::g474board::rig
