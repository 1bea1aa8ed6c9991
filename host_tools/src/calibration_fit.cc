#include "mjc/host/calibration_fit.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <limits>
#include <nlopt.hpp>
#include <string>
#include <utility>
#include <vector>

#include "mjc/host/units.h"

namespace mjc::host {
namespace {

constexpr double kMaxOffsetRad = kMaxBacklashOffset.ToDouble();
// The firmware's legal α, both bounds exclusive: (1/8, 8).
constexpr double kAlphaMin = kMinBacklashAlpha.ToDouble();
constexpr double kAlphaMax = kMaxBacklashAlpha.ToDouble();

struct PlayParams {
  double c_right;
  double c_left;
  double alpha;
  double lag_s = 0;  // joint lag T, s (0: none)
};

std::string Number(double value, int digits) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.*f", digits, value);
  return buffer;
}

// "1.2345° (0.021546 rad)".
std::string Degrees(double rad) {
  return Number(RadToDeg(rad), 4) + "° (" + Number(rad, 6) + " rad)";
}

std::string Count(std::size_t n) { return std::to_string(n); }

// One step of the play operator; lo <= hi because c_l <= c_r and α > 0.
inline double Play(double previous, double motor, const PlayParams& p) {
  return std::min(std::max(previous, p.alpha * (motor - p.c_right)),
                  p.alpha * (motor - p.c_left));
}

// Σ (θ_j − model)² over the record, the operator started at θ_j[0] clamped into the
// band; with a lag, the model is the operator's output through a first-order lag of T
// at `sample_period_s` per sample (started at the same point).
double SumSquaredError(std::span<const double> motor, std::span<const double> joint,
                       const PlayParams& p, double sample_period_s = 0) {
  double y = Play(joint[0], motor[0], p);
  double lagged = y;
  const double gain = p.lag_s > 0 && sample_period_s > 0
                          ? 1.0 - std::exp(-sample_period_s / p.lag_s)
                          : 1.0;
  double sum = 0.0;
  for (std::size_t n = 0; n < motor.size(); ++n) {
    y = Play(y, motor[n], p);
    lagged += gain * (y - lagged);
    const double e = joint[n] - lagged;
    sum += e * e;
  }
  return sum;
}

struct Engagement {
  std::size_t right = 0;  // the output rose: it follows α(θ_m − c_r)
  std::size_t left = 0;   // the output fell: it follows α(θ_m − c_l)
};

Engagement CountEngagement(std::span<const double> motor, std::span<const double> joint,
                           const PlayParams& p) {
  Engagement engagement;
  double y = Play(joint[0], motor[0], p);
  for (std::size_t n = 1; n < motor.size(); ++n) {
    const double next = Play(y, motor[n], p);
    if (next > y) ++engagement.right;
    if (next < y) ++engagement.left;
    y = next;
  }
  return engagement;
}

// Direction changes of θ_m larger than `hysteresis`.
std::size_t CountReversals(std::span<const double> motor, double hysteresis) {
  int direction = 0;
  double high = motor[0];
  double low = motor[0];
  std::size_t reversals = 0;
  for (const double x : motor) {
    high = std::max(high, x);
    low = std::min(low, x);
    if (direction >= 0 && high - x > hysteresis) {
      if (direction > 0) ++reversals;
      direction = -1;
      low = x;
    } else if (direction <= 0 && x - low > hysteresis) {
      if (direction < 0) ++reversals;
      direction = 1;
      high = x;
    }
  }
  return reversals;
}

// How far θ_m strays, between kept samples, outside the range of the two kept samples
// around it when only every stride-th sample is kept: the part of a reversal peak the
// decimated record misses.
double MissedExcursion(std::span<const double> motor, std::size_t stride) {
  double missed = 0.0;
  for (std::size_t start = 0; start + stride < motor.size(); start += stride) {
    const double a = motor[start];
    const double b = motor[start + stride];
    const double top = std::max(a, b);
    const double bottom = std::min(a, b);
    for (std::size_t n = start + 1; n < start + stride; ++n) {
      missed = std::max({missed, motor[n] - top, bottom - motor[n]});
    }
  }
  return missed;
}

std::vector<double> Decimate(std::span<const double> x, std::size_t stride) {
  std::vector<double> out;
  out.reserve(x.size() / stride + 1);
  for (std::size_t n = 0; n < x.size(); n += stride) out.push_back(x[n]);
  return out;
}

std::size_t CeilDiv(std::size_t a, std::size_t b) { return (a + b - 1) / b; }

// The optimiser's coordinates: x = (c_l, s[, α][, T]), c_r = c_l + s·(max − c_l).
PlayParams FromCoordinates(const std::vector<double>& x, bool fit_alpha,
                           double fixed_alpha, bool fit_lag = false) {
  const double c_left = x[0];
  const double c_right =
      std::min(c_left + x[1] * (kMaxOffsetRad - c_left), kMaxOffsetRad);
  const double alpha = fit_alpha ? x[2] : fixed_alpha;
  const double lag = fit_lag ? x[fit_alpha ? 3 : 2] : 0.0;
  return {c_right, c_left, alpha, lag};
}

struct Objective {
  Objective(std::span<const double> motor_rad, std::span<const double> joint_rad,
            bool fit_alpha_too, double alpha, int* evaluation_count)
      : motor(motor_rad),
        joint(joint_rad),
        fit_alpha(fit_alpha_too),
        fixed_alpha(alpha),
        evaluations(evaluation_count) {}

  std::span<const double> motor;
  std::span<const double> joint;
  bool fit_alpha = false;
  double fixed_alpha = 1.0;
  int* evaluations = nullptr;
  bool fit_lag = false;
  double sample_period_s = 0;  // of this stage's (decimated) record
  // The best point seen, kept here so a stage that ends by an NLopt exception still
  // yields its best.
  double best_cost = std::numeric_limits<double>::infinity();
  std::vector<double> best_x;
};

// Mean square error; derivative-free algorithms pass an empty gradient.
double Evaluate(const std::vector<double>& x, std::vector<double>& /*gradient*/,
                void* data) {
  auto* objective = static_cast<Objective*>(data);
  ++*objective->evaluations;
  const PlayParams p = FromCoordinates(x, objective->fit_alpha, objective->fixed_alpha,
                                       objective->fit_lag);
  const double cost =
      SumSquaredError(objective->motor, objective->joint, p, objective->sample_period_s) /
      static_cast<double>(objective->motor.size());
  if (cost < objective->best_cost) {
    objective->best_cost = cost;
    objective->best_x = x;
  }
  return cost;
}

struct StageResult {
  std::vector<double> x;
  bool hit_limit = false;
  std::string error;  // non-empty when NLopt failed
};

StageResult RunStage(nlopt::opt& optimiser, Objective& objective,
                     std::vector<double> start) {
  StageResult result;
  optimiser.set_min_objective(Evaluate, &objective);
  double cost = 0.0;
  try {
    const nlopt::result code = optimiser.optimize(start, cost);
    result.hit_limit = code == nlopt::MAXEVAL_REACHED || code == nlopt::MAXTIME_REACHED;
  } catch (const nlopt::roundoff_limited&) {
    // Progress limited by round-off: the best point is as good as the data allow.
  } catch (const std::exception& e) {
    result.error = e.what();
  }
  result.x = objective.best_x.empty() ? start : objective.best_x;
  return result;
}

std::optional<std::string> CheckOptions(const BacklashFitOptions& o) {
  const auto positive = [](double v) { return std::isfinite(v) && v > 0.0; };
  // NaN fails every comparison, so it is refused too.
  if (!o.fit_alpha && !(o.alpha > kAlphaMin && o.alpha < kAlphaMax)) {
    return "options.alpha = " + Number(o.alpha, 6) +
           " is outside the legal range (1/8, 8)";
  }
  if (o.fit_alpha && !(o.alpha_min > kAlphaMin && o.alpha_min < o.alpha_max &&
                       o.alpha_max < kAlphaMax)) {
    return "options.alpha_min = " + Number(o.alpha_min, 6) +
           ", alpha_max = " + Number(o.alpha_max, 6) +
           ": the legal range is 1/8 < alpha_min < alpha_max < 8";
  }
  if (o.global_max_samples < kMinBacklashFitSamples ||
      o.local_max_samples < kMinBacklashFitSamples) {
    return "options.global_max_samples and local_max_samples must be at least " +
           Count(kMinBacklashFitSamples);
  }
  if (o.global_max_evaluations < 10 || o.local_max_evaluations < 10) {
    return "options.global_max_evaluations and local_max_evaluations must be at least 10";
  }
  if (!positive(o.offset_tolerance_rad) || !positive(o.alpha_tolerance) ||
      !positive(o.decimation_tolerance_rad) || !positive(o.min_reversal_rad)) {
    return "options.offset_tolerance_rad, alpha_tolerance, decimation_tolerance_rad and "
           "min_reversal_rad must be finite and > 0";
  }
  if (!(o.min_engaged_fraction > 0.0 && o.min_engaged_fraction <= 0.5)) {
    return "options.min_engaged_fraction = " + Number(o.min_engaged_fraction, 4) +
           " is outside the legal range (0, 0.5]";
  }
  if (!positive(o.max_rms_error_rad)) {
    return "options.max_rms_error_rad must be finite and > 0";
  }
  if (o.fit_lag && !positive(o.sample_rate_hz)) {
    return "options.fit_lag needs sample_rate_hz > 0 (the record's sample rate)";
  }
  if (o.fit_lag && !(positive(o.max_lag_s) && o.max_lag_s <= 0.1)) {
    return "options.max_lag_s = " + Number(o.max_lag_s, 4) +
           " is outside the legal range (0, 0.1] s";
  }
  return std::nullopt;
}

std::optional<std::string> CheckInput(std::span<const double> motor,
                                      std::span<const double> joint,
                                      const BacklashFitOptions& o) {
  if (motor.size() != joint.size()) {
    return "motor_rad has " + Count(motor.size()) + " samples and joint_rad " +
           Count(joint.size()) + ": they must be pairs of the same sample instants";
  }
  if (motor.size() < kMinBacklashFitSamples) {
    return "the sweep has " + Count(motor.size()) + " samples, fewer than the " +
           Count(kMinBacklashFitSamples) + " a fit needs";
  }
  for (std::size_t n = 0; n < motor.size(); ++n) {
    if (!std::isfinite(motor[n])) {
      return "motor_rad[" + Count(n) + "] is not finite (NaN or inf)";
    }
    if (!std::isfinite(joint[n])) {
      return "joint_rad[" + Count(n) + "] is not finite (NaN or inf)";
    }
  }
  if (CountReversals(motor, o.min_reversal_rad) == 0) {
    const auto [low, high] = std::minmax_element(motor.begin(), motor.end());
    return "the motor never reverses by more than " + Degrees(o.min_reversal_rad) +
           " (motor_rad spans " + Degrees(*low) + " to " + Degrees(*high) +
           "): the cable must be driven both ways to see c_r and c_l";
  }
  return std::nullopt;
}

}  // namespace

std::string_view ToString(BacklashFitStatus status) {
  switch (status) {
    case BacklashFitStatus::kConverged:
      return "converged";
    case BacklashFitStatus::kHitLimit:
      return "hit evaluation limit";
    case BacklashFitStatus::kRefusedInput:
      return "refused input";
  }
  return "unknown";
}

BacklashFit FitBacklash(std::span<const double> motor_rad,
                        std::span<const double> joint_rad,
                        const BacklashFitOptions& options) {
  const auto start_time = std::chrono::steady_clock::now();
  BacklashFit fit;
  const auto finish = [&](BacklashFitStatus status, std::string message) {
    fit.status = status;
    fit.message = std::move(message);
    fit.elapsed_ms = std::chrono::duration<double, std::milli>(
                         std::chrono::steady_clock::now() - start_time)
                         .count();
    return fit;
  };

  if (auto why = CheckOptions(options)) {
    return finish(BacklashFitStatus::kRefusedInput, std::move(*why));
  }
  if (auto why = CheckInput(motor_rad, joint_rad, options)) {
    return finish(BacklashFitStatus::kRefusedInput, std::move(*why));
  }
  const std::size_t n = motor_rad.size();
  const bool fit_alpha = options.fit_alpha;
  const bool fit_lag = options.fit_lag;
  const std::size_t dimension = 2u + (fit_alpha ? 1u : 0u) + (fit_lag ? 1u : 0u);
  const double period = fit_lag ? 1.0 / options.sample_rate_hz : 0.0;

  std::vector<double> lower = {-kMaxOffsetRad, 0.0};
  std::vector<double> upper = {kMaxOffsetRad, 1.0};
  if (fit_alpha) {
    lower.push_back(options.alpha_min);
    upper.push_back(options.alpha_max);
  }
  if (fit_lag) {
    lower.push_back(0.0);
    upper.push_back(options.max_lag_s);
  }

  // Each stage: the cost over the record sampled every `stride`th sample, and an
  // optimiser over the legal box.
  const auto stage_objective = [&](std::span<const double> motor,
                                   std::span<const double> joint, std::size_t stride) {
    Objective objective(motor, joint, fit_alpha, options.alpha, &fit.evaluations);
    objective.fit_lag = fit_lag;
    objective.sample_period_s = period * static_cast<double>(stride);
    return objective;
  };
  const auto stage_optimiser = [&](nlopt::algorithm algorithm, int max_evaluations) {
    nlopt::opt optimiser(algorithm, static_cast<unsigned>(dimension));
    optimiser.set_lower_bounds(lower);
    optimiser.set_upper_bounds(upper);
    optimiser.set_maxeval(max_evaluations);
    return optimiser;
  };

  // Global stage: DIRECT-L over the whole legal box on a decimated copy. Its job is the
  // basin, not the digits, so a coarse stride costs nothing in the result.
  const std::size_t global_stride = CeilDiv(n, options.global_max_samples);
  const std::vector<double> global_motor = Decimate(motor_rad, global_stride);
  const std::vector<double> global_joint = Decimate(joint_rad, global_stride);
  Objective global = stage_objective(global_motor, global_joint, global_stride);
  nlopt::opt direct = stage_optimiser(nlopt::GN_DIRECT_L, options.global_max_evaluations);
  std::vector<double> middle(dimension);
  for (std::size_t i = 0; i < dimension; ++i) middle[i] = 0.5 * (lower[i] + upper[i]);
  const StageResult coarse = RunStage(direct, global, middle);
  if (!coarse.error.empty()) {
    return finish(BacklashFitStatus::kRefusedInput,
                  "the global search failed: " + coarse.error);
  }

  // Local stage: BOBYQA on the record, decimated only as far as the missed motor
  // excursion stays within tolerance.
  std::size_t stride = CeilDiv(n, options.local_max_samples);
  while (stride > 1 &&
         MissedExcursion(motor_rad, stride) > options.decimation_tolerance_rad) {
    --stride;
  }
  fit.decimation = stride;
  std::vector<double> local_motor;
  std::vector<double> local_joint;
  std::span<const double> motor = motor_rad;
  std::span<const double> joint = joint_rad;
  if (stride > 1) {
    local_motor = Decimate(motor_rad, stride);
    local_joint = Decimate(joint_rad, stride);
    motor = local_motor;
    joint = local_joint;
  }
  Objective local = stage_objective(motor, joint, stride);
  nlopt::opt bobyqa = stage_optimiser(nlopt::LN_BOBYQA, options.local_max_evaluations);
  // Steps and tolerances in the optimiser's coordinates: s moves c_r by (max − c_l)·ds.
  const double right_lever = std::max(kMaxOffsetRad - coarse.x[0], 1e-3);
  // ~0.3°: BOBYQA's first trust region around the global stage's best point, which
  // it then shrinks to the tolerance.
  constexpr double kStartStepRad = 5e-3;
  std::vector<double> step = {kStartStepRad, std::min(kStartStepRad / right_lever, 0.25)};
  std::vector<double> tolerance = {options.offset_tolerance_rad,
                                   options.offset_tolerance_rad / right_lever};
  if (fit_alpha) {
    step.push_back(0.01 * coarse.x[2]);
    tolerance.push_back(options.alpha_tolerance);
  }
  if (fit_lag) {
    step.push_back(0.1 * options.max_lag_s);
    tolerance.push_back(1e-7);  // 0.1 µs
  }
  bobyqa.set_initial_step(step);
  bobyqa.set_xtol_abs(tolerance);
  // The lag and the band's width trade against each other: a joint that trails the
  // cable side by T looks, to the operator without a lag, like a band wider on both
  // sides. The global stage can settle in that basin of no lag and a wide band, and
  // BOBYQA started there stays in it. Seen on the simulated robot with a (2.5°, 1.0°)
  // slack pair whose sweep began after the board had sat idle: both offsets 0.066° off,
  // RMS 0.044° against 0.023° in the right basin; and which basin the global stage
  // picks changed with its decimation (strides 2, 4, 5, 6 the wrong one, 3 the right
  // one), so no stride is a fix. So the local stage also starts from the global point
  // with T spread over its range in steps of three (max/27, max/9, max/3), and the
  // lowest cost of all starts wins: `local` keeps the best point of every run.
  std::vector<std::vector<double>> starts = {coarse.x};
  if (fit_lag) {
    for (const double fraction : {1.0 / 27.0, 1.0 / 9.0, 1.0 / 3.0}) {
      std::vector<double> start = coarse.x;
      start.back() = fraction * options.max_lag_s;  // T is the last coordinate
      starts.push_back(std::move(start));
    }
  }
  StageResult refined;
  bool best_hit_limit = false;  // of the run that found the best point
  for (const std::vector<double>& start : starts) {
    const double best_before = local.best_cost;
    refined = RunStage(bobyqa, local, start);
    if (!refined.error.empty()) {
      return finish(BacklashFitStatus::kRefusedInput,
                    "the local search failed: " + refined.error);
    }
    if (local.best_cost < best_before) best_hit_limit = refined.hit_limit;
  }
  refined.hit_limit = best_hit_limit;  // refined.x is already the best of all runs

  const PlayParams best = FromCoordinates(refined.x, fit_alpha, options.alpha, fit_lag);
  fit.c_right_rad = best.c_right;
  fit.c_left_rad = best.c_left;
  fit.alpha = best.alpha;
  fit.lag_s = best.lag_s;
  fit.rms_error_rad = std::sqrt(SumSquaredError(motor_rad, joint_rad, best, period) /
                                static_cast<double>(n));
  const Engagement engagement = CountEngagement(motor_rad, joint_rad, best);

  const std::string summary =
      "c_r = " + Degrees(best.c_right) + ", c_l = " + Degrees(best.c_left) +
      ", alpha = " + Number(best.alpha, 6) + (fit_alpha ? "" : " (fixed)") + ", RMS " +
      Degrees(fit.rms_error_rad) + " over " + Count(n) + " samples";

  // Identifiability: a side whose edge never moves the modelled joint leaves its offset
  // anywhere on a plateau of the cost.
  const auto needed = static_cast<std::size_t>(
      std::ceil(options.min_engaged_fraction * static_cast<double>(n)));
  const auto [motor_low, motor_high] =
      std::minmax_element(motor_rad.begin(), motor_rad.end());
  const std::string span = "the motor spans " + Degrees(*motor_low) + " to " +
                           Degrees(*motor_high) + ", the fitted dead band is " +
                           Degrees(best.c_right - best.c_left);
  const bool right_blind = engagement.right < needed;
  const bool left_blind = engagement.left < needed;
  if (right_blind || left_blind) {
    const std::string what =
        right_blind && left_blind
            ? "neither c_r nor c_l can be identified: the sweep never "
              "drives the cable across its dead band onto either edge"
        : right_blind ? "c_r cannot be identified: the sweep never drives the "
                        "cable across its dead band onto the right edge"
                      : "c_l cannot be identified: the sweep never drives the "
                        "cable across its dead band onto the left edge";
    return finish(BacklashFitStatus::kRefusedInput,
                  what + " (the right edge moves the modelled joint in " +
                      Count(engagement.right) + " and the left edge in " +
                      Count(engagement.left) + " of " + Count(n) + " samples, need " +
                      Count(needed) + " each); " + span +
                      ". Use a sweep whose amplitude exceeds the cable slack");
  }

  // A fit pinned to a legal-range bound means the data want a value beyond it.
  const double offset_margin = std::max(1e-6, 10.0 * options.offset_tolerance_rad);
  if (best.c_right >= kMaxOffsetRad - offset_margin ||
      best.c_left <= -kMaxOffsetRad + offset_margin) {
    return finish(BacklashFitStatus::kRefusedInput,
                  "the best fit puts an offset on the legal bound ±" +
                      Degrees(kMaxOffsetRad) + " (kMaxBacklashOffset): " + summary +
                      ". Check the joint and motor zero positions and the cable");
  }
  if (fit_alpha) {
    const double alpha_margin =
        std::max(1e-9, 1e-6 * (options.alpha_max - options.alpha_min));
    if (best.alpha <= options.alpha_min + alpha_margin ||
        best.alpha >= options.alpha_max - alpha_margin) {
      return finish(BacklashFitStatus::kRefusedInput,
                    "the best fit puts alpha on its search bound [" +
                        Number(options.alpha_min, 4) + ", " +
                        Number(options.alpha_max, 4) + "]: " + summary +
                        ". Widen alpha_min/alpha_max or check the pulley ratio");
    }
  }

  // A residual far above what the joint encoder resolves: whatever the optimiser found,
  // the record is not a play operator's (a joint held or stuck, an encoder slipping or
  // misread, a wrong α), and uploading it would make every later torque wrong.
  if (fit.rms_error_rad > options.max_rms_error_rad) {
    return finish(BacklashFitStatus::kRefusedInput,
                  "the residual " + Degrees(fit.rms_error_rad) +
                      " RMS is above the limit " + Degrees(options.max_rms_error_rad) +
                      " (max_rms_error_rad): the joint does not follow the modelled "
                      "cable: " +
                      summary +
                      ". Check that the joint moves freely, the encoders and "
                      "the pulley ratio");
  }

  const std::string how =
      "; " + Count(static_cast<std::size_t>(fit.evaluations)) +
      " evaluations, local stage on " +
      (stride == 1 ? std::string("every sample") : "one sample in " + Count(stride));
  if (refined.hit_limit) {
    return finish(BacklashFitStatus::kHitLimit,
                  "local stage hit its evaluation limit (" +
                      Count(static_cast<std::size_t>(options.local_max_evaluations)) +
                      "): " + summary + how);
  }
  return finish(BacklashFitStatus::kConverged, summary + how);
}

std::optional<BacklashConfig> ToFirmwareConfig(const BacklashFit& fit, std::string* why) {
  const auto refuse = [why](std::string reason) -> std::optional<BacklashConfig> {
    if (why != nullptr) *why = std::move(reason);
    return std::nullopt;
  };
  const std::string offset_range = "[" + Degrees(-kMaxOffsetRad) + ", " +
                                   Degrees(kMaxOffsetRad) + "] (±kMaxBacklashOffset)";
  if (fit.status != BacklashFitStatus::kConverged) {
    return refuse(std::string("the fit is not converged (") +
                  std::string(ToString(fit.status)) + "): " + fit.message);
  }
  if (!std::isfinite(fit.alpha)) return refuse("alpha is not finite");
  if (!std::isfinite(fit.c_right_rad)) return refuse("c_right is not finite");
  if (!std::isfinite(fit.c_left_rad)) return refuse("c_left is not finite");

  BacklashConfig config;
  config.alpha = Scale::Quantize(fit.alpha);
  config.c_right = Angle::Quantize(fit.c_right_rad);
  config.c_left = Angle::Quantize(fit.c_left_rad);
  switch (Validate(config)) {
    case BacklashConfigError::kOk:
      return config;
    case BacklashConfigError::kAlphaOutOfRange:
      return refuse("alpha = " + Number(fit.alpha, 6) +
                    " is outside the firmware's legal range (1/8, 8)");
    case BacklashConfigError::kOffsetOutOfRange:
      if (Abs(config.c_right) > kMaxBacklashOffset) {
        return refuse("c_right = " + Degrees(fit.c_right_rad) +
                      " is outside the legal range " + offset_range);
      }
      return refuse("c_left = " + Degrees(fit.c_left_rad) +
                    " is outside the legal range " + offset_range);
    case BacklashConfigError::kLeftAboveRight:
      return refuse("c_left = " + Degrees(fit.c_left_rad) + " is above c_right = " +
                    Degrees(fit.c_right_rad) + ": the legal range of c_left is [" +
                    Degrees(-kMaxOffsetRad) + ", c_right]");
    case BacklashConfigError::kFrictionOutOfRange:  // the fit leaves τ_f at 0
      return refuse("the cable friction is outside the firmware's legal range");
  }
  return refuse("the firmware refused the config with an unknown code");
}

}  // namespace mjc::host
