#include "mjc/core/attachment_model.h"

#include <algorithm>

namespace mjc {

namespace {

// round(numerator · 2^30 / denominator) for 0 ≤ numerator ≤ denominator, denominator
// > 0 and numerator < 2^33: a Coefficient in [0, 1].
std::int32_t UnitFraction(std::int64_t numerator, std::int64_t denominator) {
  return static_cast<std::int32_t>(
      ((numerator << Coefficient::kFracBits) + denominator / 2) / denominator);
}

// round(a·b / 2^30) for a Q30 factor (ties toward +∞).
std::int64_t MulQ30(std::int32_t a, std::int32_t b) {
  return fixed_detail::RoundingShiftRight(fixed_detail::WideProduct(a, b),
                                          Coefficient::kFracBits);
}

}  // namespace

std::int32_t AttachmentModel::Target(std::int32_t beta, std::int32_t offset) const {
  // |β·θ̃| ≤ 4 rad and |offset| ≤ 2 rad.
  return static_cast<std::int32_t>(MulQ30(beta, cable_) + offset);
}

void AttachmentModel::SetCoefficients(std::int32_t beta, std::int32_t gain,
                                      std::int64_t offset) {
  const std::int64_t limit = kOffsetLimit.raw();
  offset_ = static_cast<std::int32_t>(std::clamp(offset, -limit, limit));
  beta_ = beta;
  minus_gain_ = -gain;
  gain_beta_ = static_cast<std::int32_t>(MulQ30(gain, beta));
  gain_offset_ =
      std::int64_t{gain} * offset_ + (std::int64_t{1} << (Coefficient::kFracBits - 1));
}

bool AttachmentModel::Configure(Stiffness sea, const AttachmentParams& params,
                                std::uint32_t tick_hz) {
  if (!AttachmentParamsValid(params) || sea <= Stiffness{} || tick_hz == 0 ||
      tick_hz > (std::uint32_t{1} << 20)) {
    return false;
  }
  // Stiffness and Damping share Q24, so K + k and b·f_tick (N·m/rad) are raw sums:
  // K + k < 2^32, b·f < 2^51.
  const std::int64_t total = std::int64_t{sea.raw()} + params.stiffness.raw();
  const std::int64_t viscous = std::int64_t{params.damping.raw()} * tick_hz;
  const std::int32_t beta = UnitFraction(sea.raw(), total);
  const std::int32_t gain = UnitFraction(total, total + viscous);
  // The next step with the same cable side is g·(T − θ); the new coefficients make it
  // g'·(T' − θ), the same for T' = θ + (g/g')·(T − θ) (T' = θ when g' rounds to 0).
  const std::int64_t gap = std::int64_t{Target(beta_, offset_)} - angle_;
  const std::int64_t target =
      gain == 0 ? angle_ : angle_ + (gap * -minus_gain_ + gain / 2) / gain;
  SetCoefficients(beta, gain, target - MulQ30(beta, cable_));
  return true;
}

void AttachmentModel::Reset(Angle joint, Angle cable) {
  cable_ = ClampedCable(cable);
  angle_ = ClampedCable(joint);
  SetCoefficients(beta_, -minus_gain_, std::int64_t{angle_} - MulQ30(beta_, cable_));
  // The offset's clamp can leave the model off its equilibrium; it starts where its
  // target is, so that it starts at rest.
  angle_ = Target(beta_, offset_);
}

}  // namespace mjc
