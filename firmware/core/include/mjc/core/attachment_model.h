// The joint angle the attachment should give for the cable side the board sees: a
// model the velocity estimator subtracts from the measured θ_j, so that its slope only
// has to follow what the model missed (velocity_estimator.h).
//
// Why. θ̇_j is the least-squares slope of the 14-bit joint encoder over N ticks. Its
// noise falls as N^-1.5, but a long window smears the joint's kinks: where the motor
// reverses and the cable crosses its slack, θ̈_j jumps, and the slope of a window across
// that instant is biased. The cable side θ̃_j comes from the motor encoder, about ten
// times finer through the cable, and carries those kinks at the right instants. With
// the spring (K) and the attachment (Kelvin–Voigt k, b, from the board's own fit,
// interface_fit.h) in series, the joint follows the cable side as
//
//   b·θ̇ = K·(θ̃_j − θ) − k·θ + c
//
// (c: the preload and the zeros), a first-order lag toward β·θ̃_j + c/(K + k),
// β = K/(K + k), with time constant b/(K + k). The residual θ_j − θ_model is smooth
// where the model is right (its kinks are the model's own), so a window twice as long
// takes the noise down by 2.8 without the bias, and the model's own velocity is known
// exactly.
//
// Nothing depends on the model being right: θ̇_j = slope(θ_j − θ_model) + θ̇_model is
// an identity for any model sequence, and the estimate is exactly the plain slope's
// when the model stands still. A model with k 45 % and b 31 % low still cuts the plain
// 100 ms slope's power error by 40 % (2.85 → 1.74 % of peak); with both a third of the
// truth it doubles it (5.56 %) (subject 2 at 6°, 0.5 Hz: SIGNAL_CHAIN.md). Hence the
// board feeds it its own fit.
// The constant c is not identified: an offset of the model changes no slope, so the
// offset only puts the model's equilibrium where the joint was when it started
// (Reset) and keeps its velocity from jumping when a new fit arrives (Configure).
//
// Discrete form, backward Euler (stable for every b ≥ 0, b = 0 following the cable at
// once; no exponential to evaluate), with target T_n = β·θ̃_n + offset:
//   θ_n = θ_{n−1} + g·(T_n − θ_{n−1}),   g = (K + k) / (K + k + b·f_tick)
// computed as one sum of products, step = (g·β)·θ̃_n − g·θ_{n−1} + g·offset, rounded
// once. The state is a ModelAngle (Q4.27): a step at 0.2 rad/s is 2,700 LSB, and the
// rounding of a step (≤ 0.5 LSB, 3.7e-5 rad/s at 10 kHz) is a tenth of the encoder's
// noise on the slope.
#pragma once

#include <cstdint>

#include "mjc/core/fixed.h"
#include "mjc/core/quantities.h"

namespace mjc {

// An attachment's Kelvin–Voigt parameters (interface_fit.h's k_i and b_i).
struct AttachmentParams {
  Stiffness stiffness;  // k, N·m/rad: [0, 128)
  Damping damping;      // b, N·m·s/rad: [0, 128)
  friend constexpr bool operator==(const AttachmentParams&,
                                   const AttachmentParams&) = default;
};

// Whether the model accepts `params`: k ≥ 0 and b ≥ 0.
constexpr bool AttachmentParamsValid(const AttachmentParams& params) {
  return params.stiffness >= Stiffness{} && params.damping >= Damping{};
}

class AttachmentModel {
 public:
  // The cable side the model follows is clamped to ±kCableLimit and its offset to
  // ±kOffsetLimit: a finger's joint range is under 2 rad, and past the limits the model
  // only stops helping (the identity above still holds). Then every target and state
  // lies within ±6 rad, the gap between them within ±12 rad, and ModelAngle (±16 rad)
  // holds every sum of the step without a saturation test.
  // [−2^26, 2^26 − 1] raw: one SSAT on the Cortex-M4.
  static constexpr int kCableBits = 27;
  static constexpr Angle kCableLimit = Angle::FromRaw(std::int32_t{1} << 26);  // 4 rad
  static constexpr ModelAngle kOffsetLimit =
      ModelAngle::FromRaw(std::int32_t{1} << 28);  // 2 rad

  // Coefficients for the SEA stiffness `sea` (> 0, ControlConfig's), `params` and
  // `tick_hz` (1..2^20). False, changing nothing, when the params are invalid
  // (AttachmentParamsValid) or `sea` is not positive. On a model that has stepped the
  // offset is chosen so that its next step is what the old coefficients would have
  // made: a new fit bends the model's path without a jump in its velocity, which the
  // estimator's window would see.
  bool Configure(Stiffness sea, const AttachmentParams& params, std::uint32_t tick_hz);

  // Starts the model at rest at `joint` (θ_j) with the cable side at `cable`: the offset
  // makes that the model's equilibrium.
  void Reset(Angle joint, Angle cable);

  // One tick with this tick's cable side θ̃_j: moves the model and returns its step,
  // ModelAngle raw per tick. Interrupt context.
  std::int32_t ISR_Step(Angle cable) {
    cable_ = ClampedCable(cable);
    // |g·β·θ̃| ≤ 2^30·2^29, |g·θ| < 2^30·2^29.6, |g·offset| ≤ 2^30·2^28: the sum is
    // below 2^61, and the step (g times a gap within ±12 rad) fits ModelAngle, so its
    // low word after the shift is the step. The rounding's half LSB is in
    // gain_offset_: floor((sum + 2^29) / 2^30).
    const std::int64_t sum = fixed_detail::WideProduct(gain_beta_, cable_) +
                             fixed_detail::WideProduct(minus_gain_, angle_) +
                             gain_offset_;
    const auto step = static_cast<std::int32_t>(static_cast<std::uint32_t>(
        static_cast<std::uint64_t>(sum) >> Coefficient::kFracBits));
    angle_ += step;
    return step;
  }

  // θ_model after the last step.
  ModelAngle angle() const { return ModelAngle::FromRaw(angle_); }
  // β = K/(K + k) and g (above), Q1.30.
  Coefficient beta() const { return Coefficient::FromRaw(beta_); }
  Coefficient gain() const { return Coefficient::FromRaw(-minus_gain_); }
  ModelAngle offset() const { return ModelAngle::FromRaw(offset_); }

 private:
  // θ̃_j clamped to ±kCableLimit, as ModelAngle raw.
  static std::int32_t ClampedCable(Angle cable) {
    return fixed_detail::SaturateToBits<kCableBits>(cable.raw()) *
           (1 << (ModelAngle::kFracBits - Angle::kFracBits));
  }
  // β·θ̃ + offset for the last cable side, ModelAngle raw (within ±6 rad).
  std::int32_t Target(std::int32_t beta, std::int32_t offset) const;
  // Sets the offset (clamped) and the per-tick coefficients from beta_ and g.
  void SetCoefficients(std::int32_t beta, std::int32_t gain, std::int64_t offset);

  // Per tick (ISR_Step): g·β and −g (Q30), g·offset + 2^29 (Q57, with the step's
  // rounding), the state and the last clamped cable side (ModelAngle raw).
  std::int32_t gain_beta_ = 0;  // 0 with g = 0: a model that stands still
  std::int32_t minus_gain_ = 0;
  std::int64_t gain_offset_ = 0;
  std::int32_t angle_ = 0;
  std::int32_t cable_ = 0;
  // For Configure and the accessors: β (Q30) and the offset (ModelAngle raw).
  std::int32_t beta_ = 0;
  std::int32_t offset_ = 0;
};

}  // namespace mjc
