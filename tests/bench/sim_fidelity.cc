// Fidelity and speed of the simulated board, for ./bench: the calibration fit on the
// robot alone, the amplitude sweep of the three subjects and an elastic interface, all
// against plant ground truth with sensor noise on (seeded), at mjc-paper's settings.
//
//   power_rmse_pct_peak      worst trial, board power vs truth (aligned), % of peak
//   power_rmse_pct_peak_25deg  the same at 25° (the amplitude the paper tunes to)
//   power_latency_ms         how old the instant is that power refers to
//   window_energy_err_pct    worst analysed flexion: max(|ΔE_load|, |ΔE_unload|) / E_load
//   eta_err_pt               worst |η_board − η_truth| over the analysed flexions
//   eta_lossless_pt          worst |η_board| with a purely elastic interface
//   eta_lossless_truth_pt    worst |η_truth| there: windows cut at the commanded phase
//                            leave a little elastic energy between their ends at small
//                            amplitudes (the joint trails the command through the slack)
//   interface_k_err_pct      worst analysed flexion at ≥ 11° of the three subjects:
//                            |k_i − k| / k of the board's attachment fit
//                            (interface_fit.h)
//   interface_b_err_pct      the same for b_i against b
//   calib_err_deg            max |ĉ − c| of c_r, c_l
//   calib_fit_ms             the fit's wall time
//   sim_realtime_factor      simulated seconds per wall second, one joint, one core;
//                            the note gives it per second of this process's CPU time
//                            too, which other jobs on a shared machine do not dilute
//   sim_tick_ns              CPU time per simulated control tick, everything included
//                            (board, plant, bus, host library): the budget
//                            scripts/sim-profile splits by layer
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <numbers>

#include "mjc/plant/params.h"
#include "mjc/sim/scenarios.h"

int main() {
  using namespace mjc;
  using namespace mjc::sim;
  plant::PlantParams robot = plant::LoadPlantParams("default");
  robot.integration.max_step_s = 100e-6;  // mjc-paper's substep: one a tick

  const auto start = std::chrono::steady_clock::now();
  const std::clock_t start_cpu = std::clock();  // one thread runs everything below
  BusBoard board(robot, app::DefaultJointConfig());
  const CalibrationOutcome cal = RunCalibration(board, PaperCalibrationSweep());
  if (!cal.uploaded) {
    std::fprintf(stderr, "sim_fidelity: calibration failed: %s\n", cal.message.c_str());
    return 1;
  }
  double power = 0, power25 = 0, energy = 0, eta = 0, k_err = 0, b_err = 0;
  int fits = 0, unfitted = 0;
  for (const char* name : {"subject1", "subject2", "subject3"}) {
    const SubjectSweep s = RunAmplitudeSweep(board, plant::LoadPlantParams(name),
                                             {6, 8, 11, 15, 20, 25}, nullptr, 0, 1);
    for (const AmplitudePoint& p : s.points) {
      power = std::max(power, p.power_rmse_pct_peak);
      if (p.amplitude_deg == 25) power25 = std::max(power25, p.power_rmse_pct_peak);
      for (const WindowOutcome& w : p.flexions) {
        const double e = std::max(std::fabs(w.load - w.truth_load),
                                  std::fabs(w.unload - w.truth_unload));
        energy = std::max(energy, 100.0 * e / std::fabs(w.truth_load));
        eta = std::max(eta, std::fabs(w.eta - w.truth_eta));
        if (p.amplitude_deg < 11) continue;
        if (!w.fit_valid) {
          ++unfitted;
          continue;
        }
        ++fits;
        k_err = std::max(k_err, 100.0 * std::fabs(w.stiffness / s.truth.stiffness - 1));
        b_err = std::max(b_err, 100.0 * std::fabs(w.damping / s.truth.damping - 1));
      }
    }
  }
  plant::PlantParams elastic = plant::LoadPlantParams("subject1");
  elastic.interface.damping_Nm_s_per_rad = 0.0;
  const SubjectSweep lossless =
      RunAmplitudeSweep(board, elastic, {6, 8, 11, 15, 20, 25}, nullptr, 0, 1);
  double eta_lossless = 0, eta_lossless_truth = 0;
  for (const AmplitudePoint& p : lossless.points) {
    for (const WindowOutcome& w : p.flexions) {
      eta_lossless = std::max(eta_lossless, std::fabs(w.eta));
      eta_lossless_truth = std::max(eta_lossless_truth, std::fabs(w.truth_eta));
    }
  }
  const double wall =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const double cpu = static_cast<double>(std::clock() - start_cpu) / CLOCKS_PER_SEC;
  std::printf("power_rmse_pct_peak: %.2f %%\n", power);
  std::printf("power_rmse_pct_peak_25deg: %.2f %%\n", power25);
  const ControlTick& tick = board.app().control();
  std::printf("power_latency_ms: %.1f ms (the velocity window's delay, %u ticks)\n",
              1000.0 * tick.delay_ticks() / tick.config().tick_hz, tick.delay_ticks());
  std::printf("window_energy_err_pct: %.2f %%\n", energy);
  std::printf("eta_err_pt: %.2f points\n", eta);
  std::printf("eta_lossless_pt: %.2f points\n", eta_lossless);
  std::printf("eta_lossless_truth_pt: %.2f points\n", eta_lossless_truth);
  if (fits == 0 || unfitted > 0) {
    std::fprintf(stderr, "sim_fidelity: %d analysed flexion(s) at >= 11 deg had no fit\n",
                 unfitted);
    return 1;
  }
  std::printf("interface_k_err_pct: %.2f %% (worst of %d flexions at >= 11 deg)\n", k_err,
              fits);
  std::printf("interface_b_err_pct: %.2f %% (worst of %d flexions at >= 11 deg)\n", b_err,
              fits);
  std::printf("calib_err_deg: %.4f deg\n",
              std::max(std::fabs(cal.error_right_deg), std::fabs(cal.error_left_deg)));
  std::printf("calib_fit_ms: %.1f ms\n", cal.fit.elapsed_ms);
  const double simulated_s = board.plant().truth().time_s;
  std::printf("sim_realtime_factor: %.0f x (%.0f x per CPU second)\n", simulated_s / wall,
              simulated_s / cpu);
  const double ticks = simulated_s * tick.config().tick_hz;
  std::printf(
      "sim_tick_ns: %.0f ns (CPU time per simulated tick of %.0f us, %.0f ticks)\n",
      1e9 * cpu / ticks, 1e6 / tick.config().tick_hz, ticks);
  return 0;
}
