// The virtual joint board's end-to-end runs, driven over the bus by the host library as
// `mjc calibrate` and `mjc trial` drive a board, and judged against the plant's ground
// truth. Shared by tests/sim/virtual_board_test.cc (in process, the goals asserted) and
// tests/bench/virtual_board_figures.cc (over vcan0 in the kernel's VM: ./bench's
// virtual_board_* figures).
//
//  - The calibration: the sweep on the robot alone (SweepConfig + StartSweep), the
//    board's angle telemetry recorded until it is idle again, c_r and c_l fitted with
//    the joint's lag (host::RunSweep, with mjc calibrate's steps), the record to upload:
//    the one the board holds with the fitted backlash. Its error is the fit's against the
//    plant's slack (PlantParams::cable).
//  - The trial: the amplitude protocol's sine run by host::RunBoardTrial; each of the
//    middle three flexions (the paper's analysed ones) against the plant's interface
//    energy over the same ticks (EnergyTruth: the energy at the instant each tick
//    sampled), as tests/sim/bus_trial_test.cc judges the simulated board.
#pragma once

#include <cstdint>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "mjc/g474board/virtual_board.h"
#include "mjc/host/board_client.h"
#include "mjc/host/calibration_fit.h"
#include "mjc/host/trial_runner.h"
#include "mjc/plant/params.h"
#include "mjc/protocol/calibration_record.h"
#include "mjc/protocol/messages.h"

namespace mjc::g474board::rig {

// The plant's interface energy ∫τ_if·θ̇_j dt at the instant each of the firmware's ticks
// sampled it, recorded by the board's step observer from its first tick. Made before
// the board runs; the board must outlive it. Ticks count from the firmware's start, so
// a run with a reset is not recorded coherently (the tests have none).
class EnergyTruth {
 public:
  explicit EnergyTruth(VirtualBoard& board);
  // J at `tick`; nullopt when that tick was not reached.
  std::optional<double> At(std::uint32_t tick) const;

 private:
  mutable std::mutex mutex_;
  std::vector<double> energy_J_;  // index: the firmware's tick number
};

// The paper's calibration sweep on the robot alone: 30°, 0.5 Hz, ten cycles, 0.5 s of
// rest before and after (mjc-paper's and ./bench's sim_fidelity settings).
protocol::SweepConfig PaperSweep();
// The trial judged against the truth: subject 1's hand at 15°, 0.5 Hz, five
// repetitions, 0.5 s of rest (tests/sim/bus_trial_test.cc's).
protocol::TrialConfig JudgedTrial();

struct CalibrationRun {
  std::string error;  // empty: fitted, the record is usable
  std::size_t samples = 0;
  host::BacklashFit fit;
  protocol::CalibrationRecord record;
  double error_right_deg = 0, error_left_deg = 0;  // fitted − the plant's, °
  double worst_error_deg() const;
};

// Sweeps the board `client` talks to (idle, on the robot alone) and fits its backlash;
// `plant`: what the board's plant was built from.
CalibrationRun SweepAndFit(host::BoardClient& client, const protocol::SweepConfig& sweep,
                           const plant::PlantParams& plant);

struct WindowError {
  std::uint16_t repetition = 0;
  double loading_J = 0, unloading_J = 0, eta_pct = 0;
  double truth_loading_J = 0, truth_unloading_J = 0, truth_eta_pct = 0;
  // max(|ΔE_load|, |ΔE_unload|) as a share of the true loading energy, % (the
  // window_energy_err_pct of ./bench's sim_fidelity), and |Δη| in points.
  double energy_error_pct() const;
  double eta_error_pt() const;
};

struct TrialRun {
  std::string error;  // empty: completed, every analysed window judged
  host::BoardTrial trial;
  std::vector<WindowError> flexions;  // the middle three
  double worst_energy_error_pct() const;
  double worst_eta_error_pt() const;
};

// Runs `config` on the board `client` talks to (calibrated, idle) and judges the middle
// three flexions against `truth`.
TrialRun RunTrialAgainstTruth(host::BoardClient& client, const EnergyTruth& truth,
                              const protocol::TrialConfig& config);

}  // namespace mjc::g474board::rig
