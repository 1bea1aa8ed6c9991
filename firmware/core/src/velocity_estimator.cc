#include "mjc/core/velocity_estimator.h"

namespace mjc {

namespace {

// D = Σ (i − c)² = N(N² − 1)/12 over a window of N (odd) samples: below 2^30 for
// N ≤ kMaxWindow.
std::int64_t CentredSquares(std::uint16_t window) {
  const std::int64_t n = window;
  return n * (n * n - 1) / 12;
}

struct SlopeScale {
  std::int64_t multiplier = 0;
  int shift = 0;
};

// Velocity in Q20 from a slope in ModelAngle (Q27) raw per tick, 2^3·(S1 − c·S0)/D from
// the Q24 samples plus the model's step:
//   ω_raw = (2^3·(S1 − c·S0) + D·step) · f / (D · 2^7).
// The largest shift whose multiplier still fits in 30 bits (precision ≥ 2^-29); a zero
// multiplier means the window is too short for this tick rate.
SlopeScale ScaleFor(const VelocityEstimatorConfig& config) {
  const std::int64_t denominator = 128 * CentredSquares(config.window);
  SlopeScale best;
  for (int s = 32; s <= 62; ++s) {
    const std::int64_t f = config.tick_hz;
    if (f > (std::int64_t{1} << (62 - s))) break;  // f·2^s must fit
    const std::int64_t m = ((f << s) + denominator / 2) / denominator;
    if (m >= (std::int64_t{1} << 30)) break;
    best = {m, s};
  }
  return best;
}

}  // namespace

VelocityEstimatorError VelocityEstimator::Check(const VelocityEstimatorConfig& config,
                                                std::size_t capacity) {
  if (config.window % 2 == 0) return VelocityEstimatorError::kWindowEven;
  if (config.window < kMinWindow) return VelocityEstimatorError::kWindowTooShort;
  if (config.window > capacity || config.window > kMaxWindow) {
    return VelocityEstimatorError::kWindowTooLong;
  }
  if (config.tick_hz < 100 || config.tick_hz > 100000) {
    return VelocityEstimatorError::kTickRateOutOfRange;
  }
  if (ScaleFor(config).multiplier == 0) return VelocityEstimatorError::kWindowTooShort;
  return VelocityEstimatorError::kOk;
}

VelocityEstimatorError VelocityEstimator::Configure(
    const VelocityEstimatorConfig& config) {
  const VelocityEstimatorError error = Check(config, storage_.size());
  if (error != VelocityEstimatorError::kOk) return error;
  const SlopeScale scale = ScaleFor(config);
  window_ = config.window;
  d_ = static_cast<std::int32_t>(CentredSquares(config.window));
  multiplier_ = static_cast<std::int32_t>(scale.multiplier);
  shift_ = scale.shift;
  Reset(Angle{});
  return VelocityEstimatorError::kOk;
}

void VelocityEstimator::Reset(Angle angle) {
  const std::int64_t x = angle.raw();
  for (std::size_t i = 0; i < window_; ++i) storage_[i] = angle.raw();
  oldest_ = 0;
  s0_ = std::int64_t{window_} * x;
  centred_ = 0;  // Σ (i − c)·x = 0 for a constant x
}

AngularVelocity VelocityEstimator::Update(Angle angle, std::int32_t centre_step) {
  if (window_ == 0) return AngularVelocity{};
  const std::int32_t x_new = angle.raw();
  const std::int32_t x_old = storage_[oldest_];
  storage_[oldest_] = angle.raw();
  oldest_ = oldest_ + 1 == window_ ? 0 : oldest_ + 1;
  // T = S1 − c·S0 slides as T' = T − S0 + (c + 1)·x_0 + c·x_new (from the S1 and S0
  // updates in the header, with N − 1 = 2c): two 32×32 multiply-accumulates instead
  // of forming c·S0 from int64 S0 each tick (5 Cortex-M4 instructions fewer). Exact,
  // the same integer as before.
  const std::int32_t c = window_ / 2;
  centred_ = centred_ - s0_ + std::int64_t{c + 1} * x_old + std::int64_t{c} * x_new;
  s0_ = s0_ - x_old + x_new;
  // For N ≤ kMaxWindow, |2^3·T| ≤ 2^3·(N²/4)·2^31 < 2^54 and |D·step| < 2^30·2^31, so
  // the sum fits int64; multiplier_ is positive and below 2^30 (ScaleFor).
  const std::int64_t slope = centred_ * 8 + std::int64_t{d_} * centre_step;
  const std::int64_t v =
      MulShiftRoundUnsigned(slope, static_cast<std::uint32_t>(multiplier_), shift_);
  return AngularVelocity::FromRaw(fixed_detail::SaturateTo<std::int32_t>(v));
}

}  // namespace mjc
