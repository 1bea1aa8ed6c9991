#include "mjc/core/encoder.h"

#include <cstdint>
#include <limits>
#include <type_traits>

#include "mjc/core/fixed.h"
#include "mjc/core/wrapping.h"

namespace mjc {

namespace {

// The step of a 16-bit timer as WrappingDelta reads it: int16, so the tolerated range
// stated in the header is exactly that of the type.
static_assert(std::is_same_v<decltype(WrappingDelta(std::uint16_t{}, std::uint16_t{})),
                             std::int16_t>);
static_assert(kMaxQuadratureStepCounts == 32767);

// round(2π · 2^56): 59 significant bits, so its own rounding (≤ 0.5) changes a scale by
// under 1.1e-18 relative, far below the 2^-32 resolution of lsb_per_count_q32. Computed
// from π to 100 digits.
constexpr std::uint64_t kTwoPiQ56 = 452751216129820178u;

// Q32 scale limits: one count between 1 Angle LSB and 1 rad (2^24 LSB).
constexpr std::uint64_t kMinLsbPerCountQ32 = std::uint64_t{1} << 32;
constexpr std::uint64_t kMaxLsbPerCountQ32 = std::uint64_t{1} << 56;

// round((n_hi·2^64 + n_lo) / d), round half up, for 0 < d < 2^62; returns false (and
// leaves *q untouched) when the quotient exceeds `limit`. Cortex-M4 has no 128-bit type:
// this is restoring long division one numerator bit at a time. The remainder stays
// below d < 2^62, so doubling it plus one bit never overflows 64 bits.
constexpr bool DivideRounded(std::uint64_t n_hi, std::uint64_t n_lo, std::uint64_t d,
                             std::uint64_t limit, std::uint64_t* q) {
  std::uint64_t quotient = 0;
  std::uint64_t remainder = 0;
  for (int bit = 127; bit >= 0; --bit) {
    const std::uint64_t word = bit >= 64 ? n_hi : n_lo;
    remainder = (remainder << 1) | ((word >> (bit & 63)) & 1u);
    // Any quotient bit at or above 63 exceeds every limit used here.
    const bool set = remainder >= d;
    if (set) {
      if (bit >= 63) return false;
      remainder -= d;
      quotient |= std::uint64_t{1} << bit;
    }
  }
  if (remainder >= d - remainder) ++quotient;  // 2·remainder >= d, without overflow
  if (quotient > limit) return false;
  *q = quotient;
  return true;
}

// The 128-bit product a · b, as (high, low) 64-bit words, from 32-bit halves.
constexpr void Multiply64x32(std::uint64_t a, std::uint32_t b, std::uint64_t* hi,
                             std::uint64_t* lo) {
  const std::uint64_t low_part = (a & 0xFFFFFFFFu) * b;  // < 2^64
  const std::uint64_t high_part = (a >> 32) * b;         // < 2^64
  const std::uint64_t low = low_part + (high_part << 32);
  *lo = low;
  *hi = (high_part >> 32) + (low < low_part ? 1u : 0u);
}

// lsb_per_count_q32 of a config whose fields are already known to be positive, or 0 if
// the resolution is outside [1 LSB, 1 rad] a count.
constexpr std::uint64_t LsbPerCountQ32(std::int32_t counts_per_rev,
                                       std::int32_t gear_numerator,
                                       std::int32_t gear_denominator) {
  std::uint64_t n_hi = 0;
  std::uint64_t n_lo = 0;
  Multiply64x32(kTwoPiQ56, static_cast<std::uint32_t>(gear_denominator), &n_hi, &n_lo);
  // (2^31 - 1)^2 < 2^62, the divisor limit of DivideRounded.
  const std::uint64_t d = static_cast<std::uint64_t>(counts_per_rev) *
                          static_cast<std::uint64_t>(gear_numerator);
  std::uint64_t q = 0;
  if (!DivideRounded(n_hi, n_lo, d, kMaxLsbPerCountQ32, &q)) return 0;
  return q < kMinLsbPerCountQ32 ? 0 : q;
}

// Checked against an independent high-precision computation (π to 100 digits):
// 2π · 2^56 / 204800 = 2210699297508.89 and 2π · 2^56 · 65 / (2048 · 3249) =
// 4422759444077.49.
static_assert(LsbPerCountQ32(2048, 100, 1) == 2210699297509u);
static_assert(LsbPerCountQ32(2048, 3249, 65) == 4422759444077u);
// The extremes: 2^24·2π counts a pulley revolution is just under 1 LSB a count.
static_assert(LsbPerCountQ32(1 << 20, 100, 1) != 0);
static_assert(LsbPerCountQ32(1 << 20, 101, 1) == 0);
static_assert(LsbPerCountQ32(7, 1, 1) != 0);
static_assert(LsbPerCountQ32(6, 1, 1) == 0);

// Angle for the signed count c = direction · (count − offset), given a valid scale.
[[gnu::always_inline]] inline Angle ScaledCountToAngle(std::int64_t c,
                                                       const MotorEncoderScale& scale) {
  // |c| <= count_limit by one unsigned test: count_limit < 2^31 (the scale is at least
  // 2^32), and c + count_limit, taken mod 2^64, lies in [0, 2·count_limit] exactly
  // then, and above it for every other int64 c (two signed 64-bit tests cost the tick
  // 2 Cortex-M4 instructions more).
  const auto limit = static_cast<std::uint32_t>(scale.count_limit);
  if (static_cast<std::uint64_t>(c) + limit > std::uint64_t{2 * limit}) {
    return c < 0 ? Angle::Min() : Angle::Max();
  }
  // |c| · scale <= INT64_MAX by the choice of count_limit.
  const std::int64_t product = c * scale.lsb_per_count_q32;
  // round(product / 2^32) = the high word plus bit 31 of the low word: above int32 only
  // from a high word of INT32_MAX, which is also the saturated value (RoundingShiftRight
  // and SaturateTo's, in 32 bits).
  const auto high = static_cast<std::int32_t>(product >> 32);
  const auto half =
      static_cast<std::int32_t>((static_cast<std::uint64_t>(product) >> 31) & 1u);
  return Angle::FromRaw(high == std::numeric_limits<std::int32_t>::max() ? high
                                                                         : high + half);
}

}  // namespace

// ---------------------------------------------------------------------------------------
// Motor quadrature encoder
// ---------------------------------------------------------------------------------------

MotorEncoderConfigError ValidateMotorEncoderConfig(const MotorEncoderConfig& config) {
  MotorEncoderScale scale;
  return ComputeMotorEncoderScale(config, &scale);
}

MotorEncoderConfigError ComputeMotorEncoderScale(const MotorEncoderConfig& config,
                                                 MotorEncoderScale* scale) {
  *scale = MotorEncoderScale{};
  if (config.counts_per_rev <= 0) {
    return MotorEncoderConfigError::kCountsPerRevNotPositive;
  }
  if (config.gear_numerator <= 0 || config.gear_denominator <= 0) {
    return MotorEncoderConfigError::kGearRatioNotPositive;
  }
  if (config.direction != 1 && config.direction != -1) {
    return MotorEncoderConfigError::kDirectionInvalid;
  }
  const std::uint64_t q32 = LsbPerCountQ32(config.counts_per_rev, config.gear_numerator,
                                           config.gear_denominator);
  if (q32 == 0) return MotorEncoderConfigError::kResolutionOutOfRange;
  scale->lsb_per_count_q32 = static_cast<std::int64_t>(q32);
  scale->count_limit =
      std::numeric_limits<std::int64_t>::max() / scale->lsb_per_count_q32;
  return MotorEncoderConfigError::kOk;
}

void MotorEncoderState::Clear() { *this = MotorEncoderState{}; }

// CountToAngle's body, inlined into each tick's Update (GCC kept a call to a clone of
// CountToAngle there).
[[gnu::always_inline]] inline Angle MotorEncoder::AngleOf(
    std::int64_t extended_count) const {
  if (config_error_ != MotorEncoderConfigError::kOk) return Angle{};
  // Saturating subtraction: a far-away offset gives a saturated angle, not UB.
  std::int64_t c = 0;
  if (__builtin_sub_overflow(extended_count, zero_offset_counts_, &c)) {
    c = extended_count < 0 ? std::numeric_limits<std::int64_t>::min()
                           : std::numeric_limits<std::int64_t>::max();
  }
  if (direction_ < 0) {
    c = c == std::numeric_limits<std::int64_t>::min()
            ? std::numeric_limits<std::int64_t>::max()
            : -c;
  }
  return ScaledCountToAngle(c, scale_);
}

// Inlined into Update, with AngleOf: as calls they cost the tick 4 Cortex-M4
// instructions more (tick_instructions_cm4).
[[gnu::always_inline]] inline void MotorEncoder::StoreAngle() {
  state_->angle = AngleOf(state_->extended_count);
  // Max or Min: the two raw values whose sum with 2^31 + 1 is 0 or 1, mod 2^32.
  state_->angle_saturated =
      static_cast<std::uint32_t>(state_->angle.raw()) + 0x80000001u <= 1u;
}

MotorEncoder::MotorEncoder(const MotorEncoderConfig* config, MotorEncoderState* state)
    : config_(config), state_(state) {
  Reconfigure();
}

MotorEncoderConfigError MotorEncoder::Reconfigure() {
  config_error_ = ComputeMotorEncoderScale(*config_, &scale_);
  direction_ = config_->direction < 0 ? std::int8_t{-1} : std::int8_t{1};
  zero_offset_counts_ = config_->zero_offset_counts;
  StoreAngle();
  return config_error_;
}

void MotorEncoder::Reset(std::uint16_t count) {
  state_->last_count = count;
  state_->extended_count = count;
  state_->last_step_counts = 0;
  StoreAngle();
}

Angle MotorEncoder::Update(std::uint16_t count) {
  const std::int16_t step = WrappingDelta(count, state_->last_count);
  state_->last_count = count;
  state_->last_step_counts = step;
  state_->extended_count += step;
  StoreAngle();
  return state_->angle;
}

Angle MotorEncoder::CountToAngle(std::int64_t extended_count) const {
  return AngleOf(extended_count);
}

// ---------------------------------------------------------------------------------------
// Absolute joint encoder
// ---------------------------------------------------------------------------------------

JointEncoderConfigError ValidateJointEncoderConfig(const JointEncoderConfig& config) {
  if (config.zero_offset >= kJointCountsPerRev) {
    return JointEncoderConfigError::kZeroOffsetOutOfRange;
  }
  if (config.direction != 1 && config.direction != -1) {
    return JointEncoderConfigError::kDirectionInvalid;
  }
  return JointEncoderConfigError::kOk;
}

std::uint16_t EncodeJointFrame(std::uint16_t count, bool error_flag) {
  std::uint16_t frame = static_cast<std::uint16_t>(count & kJointFrameCountMask);
  if (error_flag) frame = static_cast<std::uint16_t>(frame | kJointFrameErrorFlagBit);
  if (!encoder_detail::HasEvenParity(frame)) {
    frame = static_cast<std::uint16_t>(frame | kJointFrameParityBit);
  }
  return frame;
}

}  // namespace mjc
