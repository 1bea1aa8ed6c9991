// The joint board's two position sensors, from raw hardware words to angles.
//
//  - Motor quadrature encoder: the 16-bit count of a timer in encoder mode (4 edges per
//    line), extended to a continuous int64 count and converted to the motor-PULLEY
//    angle θ_m through the gearbox.
//  - Absolute joint encoder (AS5047P class): a 16-bit SPI read frame, parity and
//    error flag checked, converted to the joint angle θ_j.
//
// Both produce mjc::Angle (Q7.24, ±128 rad, 2^-24 rad a LSB; FIXED_POINT.md). No heap,
// no floating point, no libm: every conversion is an integer multiply and a rounding
// shift, so host and Cortex-M4 give bit-identical angles.
#pragma once

#include <cstdint>
#include <limits>

#include "mjc/core/quantities.h"

namespace mjc {

// ---------------------------------------------------------------------------------------
// Motor quadrature encoder
// ---------------------------------------------------------------------------------------

// The largest timer step between two samples that is read correctly, in counts. The
// 16-bit count is extended with WrappingDelta, which returns the step modulo 2^16 as a
// value in [-32768, 32767]: a true step of +32768 or more (or below -32768) aliases
// and the extended count silently loses 65536 counts. So the motor must move FEWER than
// 32768 counts (half the timer's range) between two Update() calls.
inline constexpr std::int32_t kMaxQuadratureStepCounts =
    std::numeric_limits<std::int16_t>::max();

// The fastest motor-shaft speed, in rpm (rounded down), that the extension tracks when
// Update() runs at `sample_hz` with `counts_per_rev` quadrature edges per revolution:
// 32767 counts per sample. Both arguments must be > 0.
constexpr std::int64_t MaxTrackableMotorRpm(std::int32_t counts_per_rev,
                                            std::int32_t sample_hz) {
  return std::int64_t{kMaxQuadratureStepCounts} * sample_hz * 60 / counts_per_rev;
}

// The design point (a 10 kHz tick, docs/DESIGN.md §2; the 512-line, 2048-edge encoder of
// the shipped motor, sim_host/params/default.json's motor_counts_per_rev): the extension
// tracks up to 9.6 million motor rpm (96,000 pulley rpm at 100:1), over 300 times what
// any brushed DC motor of this size reaches (≤ 30,000 rpm, i.e. ≤ 103 counts a tick). In
// practice the timer's input filter, not the extension, limits the speed.
static_assert(MaxTrackableMotorRpm(2048, 10000) == 9'599'707);
static_assert(MaxTrackableMotorRpm(2048, 10000) > 300 * 30'000);

// Why a motor-encoder config was refused. Stable numbers: they travel over CAN and into
// logs; never renumber, only append.
enum class MotorEncoderConfigError : std::uint8_t {
  kOk = 0,
  kCountsPerRevNotPositive = 1,  // counts_per_rev <= 0
  kGearRatioNotPositive = 2,     // gear_numerator <= 0 or gear_denominator <= 0
  kDirectionInvalid = 3,         // direction is neither +1 nor -1
  // One count is finer than 1 LSB of Angle (2^-24 rad, i.e. more than 1.05e8 counts a
  // pulley revolution) or coarser than 1 rad (fewer than 6.3 counts a pulley
  // revolution). Inside these limits the conversion error bound below holds.
  kResolutionOutOfRange = 4,
};

// How motor-timer counts map to the motor-pulley angle:
//   θ_m = direction · (extended_count − zero_offset_counts) · 2π · gear_denominator /
//         (counts_per_rev · gear_numerator)   [rad]
struct MotorEncoderConfig {
  // Quadrature edges per motor-shaft revolution (4 × encoder lines). > 0.
  std::int32_t counts_per_rev = 2048;
  // Gearbox reduction, motor revolutions per pulley revolution, as an exact fraction
  // (a planetary gearhead's ratio is rational, e.g. 3249/65, not 50). Both > 0.
  std::int32_t gear_numerator = 100;
  std::int32_t gear_denominator = 1;
  // +1 if a rising timer count turns the pulley in the positive direction, else -1.
  std::int8_t direction = 1;
  // The extended count at which θ_m = 0 (set by homing). Any int64 value.
  std::int64_t zero_offset_counts = 0;
};

// The per-count conversion derived from a config once, at configure time, so that the
// per-tick conversion is one multiply and one rounding shift:
//   angle.raw = round(c · lsb_per_count_q32 / 2^32),  c = direction · (count − offset).
struct MotorEncoderScale {
  // Angle LSBs per count in Q32: round(2π · 2^56 · gear_denominator / (counts_per_rev ·
  // gear_numerator)), from a 59-bit 2π constant through a 128-bit division. In
  // [2^32, 2^56] for a valid config, zero otherwise. 514.7 LSB a count (2.2e12 here)
  // for 2048 counts at 100:1.
  std::int64_t lsb_per_count_q32 = 0;
  // The largest |c| whose product with lsb_per_count_q32 fits int64 (< 2^31 because
  // the scale is at least 1 LSB a count). Every |c| beyond it gives a saturated angle.
  std::int64_t count_limit = 0;
};

// Checks a config; kOk means the encoder can be built from it.
MotorEncoderConfigError ValidateMotorEncoderConfig(const MotorEncoderConfig& config);

// Validates `config` and, if kOk, writes its scale to *scale; otherwise leaves *scale
// zeroed. Integer only (no float), so it may run on the target; about 128 iterations of
// shift-and-subtract, not meant for the tick.
MotorEncoderConfigError ComputeMotorEncoderScale(const MotorEncoderConfig& config,
                                                 MotorEncoderScale* scale);

// Everything the encoder remembers between ticks; owned by the caller, inspected by tests
// and telemetry.
struct MotorEncoderState {
  // The timer count at the last Reset() or Update().
  std::uint16_t last_count = 0;
  // The timer count extended without wrap. Reset() sets it to the timer count itself,
  // so extended_count mod 2^16 always equals last_count. It cannot overflow in practice:
  // at the maximum trackable step every tick at 10 kHz it would take 890 years.
  std::int64_t extended_count = 0;
  // The step read at the last Update(), [-32768, 32767] counts. A supervisor compares
  // it with a plausibility limit; a step near ±32768 means the count may have aliased.
  std::int32_t last_step_counts = 0;
  // θ_m at the last Reset()/Update(); zero while the config is invalid.
  Angle angle;
  // True when `angle` is Angle::Min() or Angle::Max(): θ_m is at or beyond ±128 rad and
  // the output no longer follows the motor. The extended count keeps counting, so the
  // angle is exact again as soon as the pulley returns inside the range.
  bool angle_saturated = false;

  // Back to power-on: timer count 0, extended count 0, angle 0.
  void Clear();
};

// Extends the motor timer's count and converts it to θ_m. Call Update() once a sample,
// with fewer than 32768 counts of motion between calls (kMaxQuadratureStepCounts).
class MotorEncoder {
 public:
  // Both pointers must outlive the encoder. The config is read here and in
  // Reconfigure() only: after changing *config, call Reconfigure(). The state is not
  // cleared (call state->Clear() or Reset() for that).
  MotorEncoder(const MotorEncoderConfig* config, MotorEncoderState* state);

  // Re-reads *config and recomputes the scale (not in the tick: ~128 loop iterations).
  // With an invalid config, counts are still extended but every angle is zero until a
  // valid config is applied. Returns the validation result, also kept in
  // config_error(). Recomputes state's angle from the current extended count.
  MotorEncoderConfigError Reconfigure();

  // Starts extension at `count` (the current timer count): extended_count = count,
  // last_step_counts = 0, angle recomputed.
  void Reset(std::uint16_t count);

  // Takes the timer count sampled this tick, extends it (the step since the previous
  // sample must be in [-32768, 32767] counts; a larger true step aliases by a multiple
  // of 65536), and returns θ_m: within 0.5 + 0.25 / s LSB of the exact angle, s = the
  // scale in LSB per count (≤ 0.5005 LSB at 2048 counts, 100:1), saturated to
  // Angle::Min()/Max() beyond ±128 rad (state.angle_saturated). Zero if the config is
  // invalid.
  Angle Update(std::uint16_t count);

  // θ_m for an arbitrary extended count, with the same rounding, bound and saturation as
  // Update(); zero if the config is invalid. Does not touch the state.
  Angle CountToAngle(std::int64_t extended_count) const;

  std::int64_t extended_count() const { return state_->extended_count; }
  Angle angle() const { return state_->angle; }
  MotorEncoderConfigError config_error() const { return config_error_; }
  const MotorEncoderScale& scale() const { return scale_; }

 private:
  void StoreAngle();
  Angle AngleOf(std::int64_t extended_count) const;

  const MotorEncoderConfig* config_;
  MotorEncoderState* state_;
  // Derived from *config_ by Reconfigure().
  MotorEncoderScale scale_;
  std::int8_t direction_ = 1;
  std::int64_t zero_offset_counts_ = 0;
  MotorEncoderConfigError config_error_ = MotorEncoderConfigError::kOk;
};

// ---------------------------------------------------------------------------------------
// Absolute joint encoder (AS5047P class, 14 bits over SPI)
// ---------------------------------------------------------------------------------------

// One revolution of the joint magnet: 14-bit counts, 2π/16384 = 3.8e-4 rad (6434 Angle
// LSB) a count.
inline constexpr std::int32_t kJointCountsPerRev = 16384;

// Layout of a read frame (the sensor's response word). The parity bit makes the number
// of 1 bits in the whole 16-bit word even; EF reports that the sensor saw an error (in
// the previous command frame or internally), so the data field is not trusted.
inline constexpr std::uint16_t kJointFrameParityBit = 0x8000u;     // bit 15
inline constexpr std::uint16_t kJointFrameErrorFlagBit = 0x4000u;  // bit 14
inline constexpr std::uint16_t kJointFrameCountMask = 0x3FFFu;     // bits 13..0

// Why a joint-encoder config was refused. Stable numbers; never renumber.
enum class JointEncoderConfigError : std::uint8_t {
  kOk = 0,
  kZeroOffsetOutOfRange = 1,  // zero_offset >= 16384
  kDirectionInvalid = 2,      // direction is neither +1 nor -1
};

struct JointEncoderConfig {
  // The 14-bit count at which θ_j = 0, [0, 16383]. Only bits 13..0 are used.
  std::uint16_t zero_offset = 0;
  // +1 if a rising count is a positive joint angle, -1 if it is negative. Any negative
  // value acts as -1 and anything else as +1; ValidateJointEncoderConfig refuses both.
  std::int8_t direction = 1;
};

JointEncoderConfigError ValidateJointEncoderConfig(const JointEncoderConfig& config);

// Outcome of decoding one frame. Stable numbers: they travel over CAN and into logs.
enum class JointFrameStatus : std::uint8_t {
  kOk = 0,
  // The frame has an odd number of 1 bits: some bit was corrupted on the wire, so
  // neither EF nor the data can be trusted. Checked first.
  kParityError = 1,
  // Parity is good but the sensor raised EF: the data field is not a valid angle.
  kErrorFlag = 2,
};

struct JointSample {
  JointFrameStatus status = JointFrameStatus::kOk;
  // The frame's 14-bit angle count (before zero offset and direction), [0, 16383].
  // Zero unless status is kOk.
  std::uint16_t count = 0;
  // θ_j, in [-π, π) for direction +1 and (-π, π] for -1, within 0.5 LSB of the exact
  // value. Zero unless status is kOk: a corrupted frame never yields an angle, and the
  // decoder keeps no history, so holding the last good angle is the caller's choice.
  Angle angle;
};

// The joint angle of a 14-bit count: ((count − zero_offset) mod 16384) taken into
// [-8192, 8192) counts, times direction, times 2π/16384 rad. Bits of `count` above bit
// 13 are ignored. Within 0.5 LSB of the exact angle for every count.
Angle JointCountToAngle(std::uint16_t count, const JointEncoderConfig& config);

// Checks parity, then EF, then converts the count (JointCountToAngle).
JointSample DecodeJointFrame(std::uint16_t frame, const JointEncoderConfig& config);

// The valid frame a sensor would send for `count` (bits above 13 are dropped) and
// `error_flag`, with the parity bit set so the frame's number of 1 bits is even. For
// tests and the simulator's sensor model.
std::uint16_t EncodeJointFrame(std::uint16_t count, bool error_flag);

// The joint frame's decoding is inline: the tick reads its result in registers, and as
// a call returning the JointSample through memory it cost the tick 14 Cortex-M4
// instructions more (tick_instructions_cm4).
namespace encoder_detail {

// Even parity over all 16 bits: true when the number of 1 bits is even. XOR folding
// rather than std::popcount, which is a library call on Cortex-M4.
constexpr bool HasEvenParity(std::uint16_t word) {
  std::uint32_t x = word;
  x ^= x >> 8;
  x ^= x >> 4;
  x ^= x >> 2;
  x ^= x >> 1;
  return (x & 1u) == 0;
}

// round(2π/16384 · 2^24 · 2^37) = round(2π · 2^47): the joint scale in Angle LSB a count,
// Q37. |c| ≤ 8192 = 2^13 and the constant is below 2^50, so c · constant fits int64.
// The constant's rounding (≤ 0.5 in Q37) moves an angle by at most 8192 · 2^-38 = 3e-8
// LSB, and no exact angle c · 2π · 2^10 lies that close to a rounding tie (checked for
// all 16384 counts by the test vectors), so every angle is the correctly rounded one.
inline constexpr std::int64_t kJointLsbPerCountQ37 = 884279719003555;
inline constexpr int kJointScaleShift = 37;
static_assert(kJointLsbPerCountQ37 < (std::int64_t{1} << 50));
// The constant as high·2^32 + low with both halves in int32: c · constant is then one
// SMULL (c · low) and one MLA (c · high into the high word), exactly, where a 64-bit
// constant took four multiplies and adds. |c · high| <= 8192 · 205887 < 2^31.
inline constexpr std::int32_t kJointLsbPerCountQ37High = 205887;
inline constexpr std::int32_t kJointLsbPerCountQ37Low = 1787332003;
static_assert((std::int64_t{kJointLsbPerCountQ37High} << 32) + kJointLsbPerCountQ37Low ==
              kJointLsbPerCountQ37);
static_assert(std::int64_t{8192} * kJointLsbPerCountQ37High < (std::int64_t{1} << 31));

}  // namespace encoder_detail

inline Angle JointCountToAngle(std::uint16_t count, const JointEncoderConfig& config) {
  // (count − offset) mod 16384 through unsigned wrap, then into [-8192, 8192).
  // The low 14 bits of the difference, sign-extended (one SBFX on Cortex-M4).
  const std::uint32_t delta = std::uint32_t{count} - std::uint32_t{config.zero_offset};
  std::int32_t c = static_cast<std::int32_t>(delta << 18) >> 18;
  if (config.direction < 0) c = -c;
  // c · kJointLsbPerCountQ37, exactly (the split above).
  const std::int64_t product =
      fixed_detail::WideProduct(c, encoder_detail::kJointLsbPerCountQ37Low) +
      static_cast<std::int64_t>(static_cast<std::uint64_t>(static_cast<std::uint32_t>(
                                    c * encoder_detail::kJointLsbPerCountQ37High))
                                << 32);
  // |c · 2π/16384| ≤ π rad: far inside Angle's range, the cast cannot truncate.
  return Angle::FromRaw(static_cast<std::int32_t>(
      fixed_detail::RoundingShiftRight(product, encoder_detail::kJointScaleShift)));
}

inline JointSample DecodeJointFrame(std::uint16_t frame,
                                    const JointEncoderConfig& config) {
  JointSample sample;
  if (!encoder_detail::HasEvenParity(frame)) {
    sample.status = JointFrameStatus::kParityError;
    return sample;
  }
  if ((frame & kJointFrameErrorFlagBit) != 0) {
    sample.status = JointFrameStatus::kErrorFlag;
    return sample;
  }
  sample.status = JointFrameStatus::kOk;
  sample.count = static_cast<std::uint16_t>(frame & kJointFrameCountMask);
  sample.angle = JointCountToAngle(sample.count, config);
  return sample;
}

}  // namespace mjc
