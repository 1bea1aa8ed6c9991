// Backlash calibration: fits the firmware's play operator (mjc/core/backlash.h, the
// paper's eq. 4) to a sweep recorded on the robot alone (docs/DESIGN.md §5 "Calibration",
// the paper's Fig. 7), then converts the fit into the firmware's fixed-point config.
//
// The model, in double precision, with the joint's first reading as initial state:
//   θ̃[0] = clamp(θ_j[0], α(θ_m[0] − c_r), α(θ_m[0] − c_l))
//   θ̃[n] = clamp(θ̃[n−1], α(θ_m[n] − c_r), α(θ_m[n] − c_l))
// and the fit minimises RMS(θ_j − θ̃) over c_r, c_l (and α when asked) within the
// firmware's legal ranges: −kMaxBacklashOffset <= c_l <= c_r <= +kMaxBacklashOffset,
// 0 < α < 8.
//
// Search: a global stage (NLopt's DIRECT-L) on a decimated copy finds the basin, since
// the cost has plateaus wherever the dead band is wider than the sweep; a local stage
// (BOBYQA) then refines on the whole record. The optimiser works in (c_l, s) with
// c_r = c_l + s·(kMaxBacklashOffset − c_l), s in [0, 1], so the legal triangle
// c_l <= c_r <= max is a box and both stages can use plain bounds.
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>
#include <numbers>
#include <optional>
#include <span>
#include <string>
#include <string_view>

#include "mjc/core/backlash.h"

namespace mjc::host {

// Fewest samples FitBacklash accepts. A usable sweep (several cycles of growing
// amplitude) has thousands; below this there is nothing to fit.
inline constexpr std::size_t kMinBacklashFitSamples = 100;

enum class BacklashFitStatus : std::uint8_t {
  // The local stage met its tolerances; the values are the fit.
  kConverged = 0,
  // The local stage ran out of evaluations before its tolerances were met; the values
  // are the best found, and ToFirmwareConfig refuses them.
  kHitLimit = 1,
  // Bad data, bad options, a sweep that cannot identify c_r and c_l, or a best fit that
  // sits on a legal-range bound; `message` says which.
  kRefusedInput = 2,
};

std::string_view ToString(BacklashFitStatus status);

struct BacklashFitOptions {
  // Fit α = r_m / r_j as well; otherwise `alpha` is used as given.
  bool fit_alpha = false;
  // The fixed α when fit_alpha is false. Legal (1/8, 8), the firmware's range.
  double alpha = 1.0;
  // α's search range when fit_alpha is true. Legal 1/8 < alpha_min < alpha_max < 8. A fit
  // that ends on either bound is refused (widen the range).
  double alpha_min = 0.5;
  double alpha_max = 2.0;

  // Fit a first-order lag T between the cable side and the measured joint as well:
  // θ_j follows BL(θ_m) through y[n] = y[n−1] + (1 − e^(−dt/T))·(BL[n] − y[n−1]). On the
  // robot alone the SEA spring drives the joint against its own damping, so the joint
  // trails the cable side by T ≈ b_j / (2kr_j²) (a few ms); a play-only fit reads that
  // trail as extra slack on both sides. Needs sample_rate_hz. T is searched in
  // [0, max_lag_s] (legal (0, 0.1] s).
  bool fit_lag = false;
  double sample_rate_hz = 0;  // of motor_rad/joint_rad; legal > 0 when fit_lag
  double max_lag_s = 0.02;

  // Global stage: DIRECT-L on a copy decimated (every k-th sample) to at most
  // global_max_samples (legal >= kMinBacklashFitSamples), for global_max_evaluations
  // cost evaluations (legal >= 10; DIRECT-L uses them all).
  std::size_t global_max_samples = 4000;
  int global_max_evaluations = 1000;

  // Local stage: BOBYQA on the record, decimated only when it is longer than
  // local_max_samples (legal >= kMinBacklashFitSamples), and then only with a stride
  // that skips no motor excursion larger than decimation_tolerance_rad (legal > 0 rad)
  // beyond the kept samples: a missed reversal peak shifts the held output by at most
  // α times that. At most local_max_evaluations (legal >= 10) cost evaluations.
  std::size_t local_max_samples = 50000;
  int local_max_evaluations = 2000;
  double decimation_tolerance_rad = 1e-4;

  // The local stage stops when a step moves c_r and c_l by less than
  // offset_tolerance_rad and α by less than alpha_tolerance. Legal > 0.
  double offset_tolerance_rad = 1e-7;
  double alpha_tolerance = 1e-7;

  // A motor direction change counts as a reversal only once θ_m has come back by more
  // than this from its last extreme, so encoder noise at standstill does not count.
  // Legal > 0 rad; the default (0.057°) is ~30 counts of a 2048-CPR, 100:1 motor.
  double min_reversal_rad = 1e-3;

  // Identifiability: at the fit, each cable side must move the modelled joint (the
  // output follows that edge of the band and changes) in at least this fraction of the
  // samples, or its offset is not determined by the data. Legal (0, 0.5].
  double min_engaged_fraction = 0.02;
  // Plausibility: the fit's residual RMS (θ_j − θ̃) must not exceed this, or the fit is
  // refused. Legal > 0 rad. The default is ten counts of the 14-bit joint encoder
  // (10 · 2π/16384 = 0.22°); a good fit on the simulated robot with sensor noise reads
  // about one count (mjc-paper --scenario calibration: rms 0.023°).
  double max_rms_error_rad = 10.0 * 2.0 * std::numbers::pi / 16384.0;
};

struct BacklashFit {
  BacklashFitStatus status = BacklashFitStatus::kRefusedInput;
  // c_r and c_l in rad, c_l <= c_r, within ±kMaxBacklashOffset; α dimensionless.
  // NaN when the input was refused before fitting.
  double c_right_rad = std::numeric_limits<double>::quiet_NaN();
  double c_left_rad = std::numeric_limits<double>::quiet_NaN();
  double alpha = std::numeric_limits<double>::quiet_NaN();
  double lag_s = 0;  // the fitted joint lag T (0 when not fitted)
  // RMS of θ_j − θ̃ over the whole record at the fitted values, rad.
  double rms_error_rad = std::numeric_limits<double>::quiet_NaN();
  // Stride of the local stage's decimation (1: every sample).
  std::size_t decimation = 1;
  // Cost evaluations over both stages, and wall-clock time of the whole call in ms.
  int evaluations = 0;
  double elapsed_ms = 0.0;
  // One line for a person: the fit, or why it was refused.
  std::string message;
};

// Fits c_r, c_l (and α when options.fit_alpha) to a calibration sweep: motor_rad is
// θ_m (motor-pulley angle, rad) and joint_rad is θ_j (joint angle, rad), one pair per
// sample, same length, at the tick rate or decimated evenly. Bad input or options give
// status kRefusedInput with the reason in `message`; it never throws for bad data.
BacklashFit FitBacklash(std::span<const double> motor_rad,
                        std::span<const double> joint_rad,
                        const BacklashFitOptions& options = {});

// The fit as the firmware's fixed-point config (α as Scale Q3.28, c as Angle Q7.24,
// rounded to nearest), checked with mjc::Validate. Refuses (nullopt, and the reason in
// *why when why is not null) a fit that did not converge, non-finite values, α outside
// (1/8, 8), an offset outside ±kMaxBacklashOffset, and c_l > c_r; the reason names the
// field, its value and its legal range.
std::optional<BacklashConfig> ToFirmwareConfig(const BacklashFit& fit, std::string* why);

}  // namespace mjc::host
