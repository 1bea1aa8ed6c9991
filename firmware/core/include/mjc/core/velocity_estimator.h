// Joint velocity θ̇_j by a sliding least-squares slope (the first-derivative
// Savitzky–Golay filter) over the last N ticks, and the delay line that aligns the
// torque with it.
//
// Why this estimator and not an observer: interface power is τ·θ̇_j, and any lag
// between τ and θ̇_j reads as false energy loss (5 ms at 0.5 Hz is ~5 points of η). An
// α-β-γ or steady-state Kalman observer lags by an amount that depends on frequency, so
// no fixed delay of τ aligns them for every motion. The least-squares slope has exactly
// linear phase: its group delay is (N−1)/2 ticks at every frequency, and delaying τ by
// the same (N−1)/2 ticks aligns the two exactly. It is also cheap and exact: the
// window sums S0 = Σx_i and S1 = Σ i·x_i update in O(1) per tick in int64 with no
// rounding (x_i are raw Q24 angles), so nothing drifts however long it runs.
//
//   slope = Σ (i − c)·x_i / D,  c = (N−1)/2,  D = Σ (i − c)² = N(N²−1)/12
//   Σ (i − c)·x_i = S1 − c·S0
//   sliding by one sample (x_0 leaves, x_new enters):
//     S1' = S1 − S0 + x_0 + (N−1)·x_new,   S0' = S0 − x_0 + x_new
//
// Noise: with a 14-bit joint encoder (step q = 3.8e-4 rad) the slope's standard
// deviation is about q·√(12/N³)/(√12·dt) — 1.2e-4 rad/s for N = 1001 at 10 kHz from
// the quantisation alone (the simulated encoder's 0.7 counts of noise make it 3.3e-4);
// the amplitude error on a 0.5 Hz sinusoid is 1 − 3(sin x − x cos x)/x³ ≈ x²/10 with
// x = πf·N·dt: 0.25 % for N = 1001, on whatever the samples hold. The tick feeds it
// θ_j less the attachment model (attachment_model.h) and adds the model's velocity at
// the centre (Update's centre_step): the slope then follows only what the model
// missed, and the joint's kinks at the cable's slack do not bias a window this long.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

#include "mjc/core/quantities.h"

namespace mjc {

struct VelocityEstimatorConfig {
  // Window length N in ticks: odd, kMinWindow..storage size (and kMaxWindow). 501 at
  // 10 kHz is a 50 ms window and a 25 ms delay; the tick's default is 1001
  // (ControlConfig::velocity_window, SIGNAL_CHAIN.md).
  std::uint16_t window = 501;
  std::uint32_t tick_hz = 10000;  // 100..100000
};

enum class VelocityEstimatorError : std::uint8_t {
  kOk = 0,
  kWindowEven = 1,
  kWindowTooShort = 2,
  kWindowTooLong = 3,  // longer than the storage given
  kTickRateOutOfRange = 4,
};

class VelocityEstimator {
 public:
  // 3.3 ms at 10 kHz: shorter windows only differentiate encoder steps. Configure()
  // also refuses a window whose 1/(D·dt) scale does not fit its multiplier (below 35
  // ticks at 100 kHz).
  static constexpr std::uint16_t kMinWindow = 33;
  // 205 ms at 10 kHz; keeps the sums of Update() within int64.
  static constexpr std::uint16_t kMaxWindow = 2047;

  // `storage` holds the window's samples; it must outlive the estimator.
  explicit VelocityEstimator(std::span<std::int32_t> storage) : storage_(storage) {}

  // Validates and applies a config; on error the previous config stays.
  VelocityEstimatorError Configure(const VelocityEstimatorConfig& config);

  // The same validation without an estimator: for storage of `capacity` samples.
  static VelocityEstimatorError Check(const VelocityEstimatorConfig& config,
                                      std::size_t capacity);

  // Fills the window with a constant angle: velocity reads zero from the next update.
  void Reset(Angle angle);

  // One tick: the newest sample in, the slope at the window's centre plus
  // `centre_step` out, i.e. the velocity delay_ticks() ticks ago. `centre_step` is a
  // known part of the velocity at the centre, in ModelAngle raw per tick: the step of
  // the model whose residual the samples are (attachment_model.h), 0 for a plain slope.
  // Saturates at the AngularVelocity range. Reads zero until Configure() succeeded.
  AngularVelocity Update(Angle angle, std::int32_t centre_step = 0);

  // The sample delay_ticks() old (the window's centre): the angle the last Update()'s
  // velocity refers to. Zero until Configure() succeeded.
  Angle centre() const {
    if (window_ == 0) return Angle{};
    const std::size_t i = oldest_ + window_ / 2;
    return Angle::FromRaw(storage_[i >= window_ ? i - window_ : i]);
  }

  // (N−1)/2: how many ticks the estimate lags the newest sample.
  std::uint16_t delay_ticks() const { return static_cast<std::uint16_t>(window_ / 2); }
  std::uint16_t window() const { return window_; }

 private:
  std::span<std::int32_t> storage_;
  std::uint16_t window_ = 0;
  std::int32_t multiplier_ = 0;  // f_tick / (128·D) as multiplier_ / 2^shift_
  std::int32_t d_ = 0;           // D = N(N²−1)/12
  int shift_ = 32;
  std::size_t oldest_ = 0;
  std::int64_t s0_ = 0;
  std::int64_t centred_ = 0;  // S1 − c·S0
};

}  // namespace mjc
