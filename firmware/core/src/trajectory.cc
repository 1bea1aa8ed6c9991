#include "mjc/core/trajectory.h"

#include <cstdint>
#include <limits>

#include "mjc/core/fixed.h"
#include "mjc/core/trig.h"

namespace mjc {

namespace {

constexpr std::uint32_t kQuarterTurn = std::uint32_t{1} << 30;

// round(π/2 · 2^32): relative error 7e-11, far below the 2^-20 rad/s of the result.
constexpr std::uint64_t kHalfPiQ32 = 6746518852u;

constexpr Segment kQuadrantSegment[4] = {
    Segment::kFlexionLoading, Segment::kFlexionUnloading, Segment::kExtensionLoading,
    Segment::kExtensionUnloading};

// A stream's velocity: an Angle step per tick times f_tick, Q24 rad/s in int64.
using WideAngularVelocity = Fixed<RadianPerSecond, 24, std::int64_t>;

constexpr bool TickRateValid(std::uint32_t tick_rate_hz) {
  return tick_rate_hz >= 1 && tick_rate_hz <= kMaxTickRateHz;
}

// floor(max_rate / f_tick) in Angle raw (Q20 -> Q24): rounding down keeps every step
// within max_rate·dt. 0 when max_rate·dt is below 1 LSB of Angle.
std::int64_t StreamStep(AngularVelocity max_rate, std::uint32_t tick_rate_hz) {
  return (std::int64_t{max_rate.raw()}
          << (Angle::kFracBits - AngularVelocity::kFracBits)) /
         tick_rate_hz;
}

// round(A·ω) in AngularVelocity raw, ω = 2π·f_tick/N = (π/2)·f_tick/Q, for
// 0 <= A <= kMaxTrajectoryAmplitude (raw < 2^25.7). Wider than int32 when the config
// is out of range; the caller checks.
std::uint64_t PeakVelocityRaw(Angle amplitude, std::uint32_t quarter_ticks,
                              std::uint32_t tick_rate_hz) {
  // A·π/2 in Q56 (< 2^58.4), then Q44 (< 2^46.4) so that times f_tick (< 2^16) fits.
  std::uint64_t v = static_cast<std::uint64_t>(amplitude.raw()) * kHalfPiQ32;
  v = (v + (std::uint64_t{1} << 11)) >> 12;
  v *= tick_rate_hz;
  // Q44 / Q -> Q20: divide by Q·2^24 (<= 2^54), rounding to nearest.
  const std::uint64_t divisor = std::uint64_t{quarter_ticks}
                                << (44 - AngularVelocity::kFracBits);
  return (v + divisor / 2u) / divisor;
}

// round(|Δ| · f_tick / ticks) in AngularVelocity raw (Angle raw per tick -> Q20), with
// Δ's sign: the sweep's d amplitude / dt. |Δ| < 2^26 and ticks < 2^48, no overflow.
std::int64_t RampRateRaw(std::int64_t delta, std::uint64_t ticks,
                         std::uint32_t tick_rate_hz) {
  const std::uint64_t magnitude = delta < 0 ? 0u - static_cast<std::uint64_t>(delta)
                                            : static_cast<std::uint64_t>(delta);
  const std::uint64_t divisor = ticks << (Angle::kFracBits - AngularVelocity::kFracBits);
  const auto rate =
      static_cast<std::int64_t>((magnitude * tick_rate_hz + divisor / 2u) / divisor);
  return delta < 0 ? -rate : rate;
}

// The checks shared by the sine (start == end amplitude) and the sweep.
TrajectoryError ValidateOscillation(Angle neutral, Angle start_amplitude,
                                    Angle end_amplitude, Frequency frequency,
                                    std::uint16_t repetitions, std::uint32_t rest_ms,
                                    std::uint32_t tick_rate_hz) {
  if (!TickRateValid(tick_rate_hz)) return TrajectoryError::kTickRateOutOfRange;
  if (end_amplitude <= Angle{}) return TrajectoryError::kAmplitudeNotPositive;
  if (start_amplitude < Angle{}) return TrajectoryError::kAmplitudeNegative;
  if (start_amplitude > kMaxTrajectoryAmplitude ||
      end_amplitude > kMaxTrajectoryAmplitude) {
    return TrajectoryError::kAmplitudeTooLarge;
  }
  if (frequency <= Frequency{}) return TrajectoryError::kFrequencyNotPositive;
  if (4u * static_cast<std::uint64_t>(frequency.raw()) >
      (std::uint64_t{tick_rate_hz} << Frequency::kFracBits)) {
    return TrajectoryError::kFrequencyTooHigh;
  }
  if (repetitions == 0) return TrajectoryError::kZeroRepetitions;
  if (rest_ms > kMaxRestMs) return TrajectoryError::kRestTooLong;

  const Angle amplitude =
      start_amplitude > end_amplitude ? start_amplitude : end_amplitude;
  const std::int64_t high = std::int64_t{neutral.raw()} + amplitude.raw();
  const std::int64_t low = std::int64_t{neutral.raw()} - amplitude.raw();
  if (high > std::numeric_limits<std::int32_t>::max() ||
      low < std::numeric_limits<std::int32_t>::min()) {
    return TrajectoryError::kSetpointOutOfRange;
  }

  // |velocity| <= A·ω + |dA/dt| (the two terms are in quadrature, so this is safe).
  const std::uint32_t quarter_ticks = QuarterTicks(frequency, tick_rate_hz);
  const std::uint64_t cycle_ticks = std::uint64_t{4} * quarter_ticks;
  const std::uint64_t peak = PeakVelocityRaw(amplitude, quarter_ticks, tick_rate_hz);
  const std::int64_t slope =
      RampRateRaw(std::int64_t{end_amplitude.raw()} - start_amplitude.raw(),
                  cycle_ticks * repetitions, tick_rate_hz);
  const std::uint64_t slope_magnitude =
      static_cast<std::uint64_t>(slope < 0 ? -slope : slope);
  if (peak + slope_magnitude >
      static_cast<std::uint64_t>(std::numeric_limits<std::int32_t>::max())) {
    return TrajectoryError::kVelocityOutOfRange;
  }
  return TrajectoryError::kOk;
}

}  // namespace

std::uint32_t QuarterTicks(Frequency frequency, std::uint32_t tick_rate_hz) {
  const auto f = static_cast<std::uint64_t>(frequency.raw());
  const std::uint64_t numerator = std::uint64_t{tick_rate_hz} << Frequency::kFracBits;
  return static_cast<std::uint32_t>((numerator + 2u * f) / (4u * f));
}

TrajectoryError ValidateStreamRate(AngularVelocity max_rate, std::uint32_t tick_rate_hz) {
  if (!TickRateValid(tick_rate_hz)) return TrajectoryError::kTickRateOutOfRange;
  if (max_rate <= AngularVelocity{}) return TrajectoryError::kRateNotPositive;
  if (StreamStep(max_rate, tick_rate_hz) < 1)
    return TrajectoryError::kRateBelowResolution;
  return TrajectoryError::kOk;
}

TrajectoryError Validate(const SineConfig& config) {
  return ValidateOscillation(config.neutral, config.amplitude, config.amplitude,
                             config.frequency, config.repetitions, config.rest_ms,
                             config.tick_rate_hz);
}

TrajectoryError Validate(const RampedSineConfig& config) {
  return ValidateOscillation(config.neutral, config.start_amplitude, config.end_amplitude,
                             config.frequency, config.repetitions, config.rest_ms,
                             config.tick_rate_hz);
}

namespace trajectory_detail {

LinearRamp::LinearRamp(std::int32_t start, std::int32_t end, std::uint64_t ticks)
    : value_(start), ticks_(ticks) {
  const std::int64_t delta = std::int64_t{end} - start;
  const auto signed_ticks = static_cast<std::int64_t>(ticks);
  quotient_ = delta / signed_ticks;  // truncates toward zero; make it floor
  std::int64_t remainder = delta - quotient_ * signed_ticks;
  if (remainder < 0) {
    remainder += signed_ticks;
    --quotient_;
  }
  remainder_ = static_cast<std::uint64_t>(remainder);
  // Starting half a step in rounds to nearest instead of down.
  accumulator_ = ticks / 2u;
}

void LinearRamp::Advance() {
  value_ += quotient_;
  accumulator_ += remainder_;
  if (accumulator_ >= ticks_) {
    accumulator_ -= ticks_;
    ++value_;
  }
}

}  // namespace trajectory_detail

TrajectoryError TrajectoryGenerator::StartSine(const SineConfig& config) {
  return StartOscillation(TrajectoryMode::kSine, config.neutral, config.amplitude,
                          config.amplitude, config.frequency, config.repetitions,
                          config.rest_ms, config.tick_rate_hz);
}

TrajectoryError TrajectoryGenerator::StartSweep(const RampedSineConfig& config) {
  return StartOscillation(TrajectoryMode::kSweep, config.neutral, config.start_amplitude,
                          config.end_amplitude, config.frequency, config.repetitions,
                          config.rest_ms, config.tick_rate_hz);
}

TrajectoryError TrajectoryGenerator::StartOscillation(
    TrajectoryMode mode, Angle neutral, Angle start_amplitude, Angle end_amplitude,
    Frequency frequency, std::uint16_t repetitions, std::uint32_t rest_ms,
    std::uint32_t tick_rate_hz) {
  const TrajectoryError error =
      ValidateOscillation(neutral, start_amplitude, end_amplitude, frequency, repetitions,
                          rest_ms, tick_rate_hz);
  if (error != TrajectoryError::kOk) return error;
  if (tick_rate_hz != tick_rate_hz_) return TrajectoryError::kTickRateMismatch;

  const std::uint32_t quarter_ticks = QuarterTicks(frequency, tick_rate_hz);
  const std::uint64_t ramp_ticks = std::uint64_t{4} * quarter_ticks * repetitions;
  // Validation bounded both peak velocities and the slope to int32.
  const auto start_velocity = static_cast<std::int32_t>(
      PeakVelocityRaw(start_amplitude, quarter_ticks, tick_rate_hz));
  const auto end_velocity = static_cast<std::int32_t>(
      PeakVelocityRaw(end_amplitude, quarter_ticks, tick_rate_hz));
  const auto slope = static_cast<std::int32_t>(
      RampRateRaw(std::int64_t{end_amplitude.raw()} - start_amplitude.raw(), ramp_ticks,
                  tick_rate_hz));

  mode_ = mode;
  repetition_ = 0;
  neutral_ = neutral;
  amplitude_ = trajectory_detail::LinearRamp(start_amplitude.raw(), end_amplitude.raw(),
                                             ramp_ticks);
  peak_velocity_ =
      trajectory_detail::LinearRamp(start_velocity, end_velocity, ramp_ticks);
  amplitude_rate_ = AngularVelocity::FromRaw(slope);
  ramping_ = start_amplitude != end_amplitude;
  quarter_ticks_ = quarter_ticks;
  phase_step_ = kQuarterTurn / quarter_ticks;
  phase_remainder_ = kQuarterTurn % quarter_ticks;
  tick_in_quarter_ = 0;
  phase_offset_ = 0;
  phase_accumulator_ = 0;
  quadrant_ = 0;
  // rest_ms·f_tick <= 60,000 · 65,535 < 2^32.
  rest_ticks_ =
      static_cast<std::uint32_t>((std::uint64_t{rest_ms} * tick_rate_hz + 500u) / 1000u);
  rest_left_ = rest_ticks_;
  repetitions_ = repetitions;
  stage_ = Stage::kLeadingRest;
  return TrajectoryError::kOk;
}

void TrajectoryGenerator::Hold(Angle position) {
  mode_ = TrajectoryMode::kHold;
  position_ = position;
  repetition_ = 0;
}

TrajectoryError TrajectoryGenerator::StartStream(Angle from, AngularVelocity max_rate) {
  const TrajectoryError error = ValidateStreamRate(max_rate, tick_rate_hz_);
  if (error != TrajectoryError::kOk) return error;
  const std::int64_t step = StreamStep(max_rate, tick_rate_hz_);
  mode_ = TrajectoryMode::kStream;
  position_ = from;
  target_ = from;
  repetition_ = 0;
  max_step_ = step > std::numeric_limits<std::int32_t>::max()
                  ? std::numeric_limits<std::int32_t>::max()
                  : static_cast<std::int32_t>(step);
  return TrajectoryError::kOk;
}

TrajectoryError TrajectoryGenerator::SetStreamTarget(Angle target) {
  if (mode_ != TrajectoryMode::kStream) return TrajectoryError::kNotStreaming;
  target_ = target;
  return TrajectoryError::kOk;
}

void TrajectoryGenerator::Stop() {
  mode_ = TrajectoryMode::kIdle;
  repetition_ = 0;
}

std::uint32_t TrajectoryGenerator::ticks_per_cycle() const {
  const bool oscillating =
      mode_ == TrajectoryMode::kSine || mode_ == TrajectoryMode::kSweep;
  return oscillating ? 4u * quarter_ticks_ : 0u;
}

std::uint32_t TrajectoryGenerator::rest_ticks() const {
  const bool oscillating =
      mode_ == TrajectoryMode::kSine || mode_ == TrajectoryMode::kSweep;
  return oscillating ? rest_ticks_ : 0u;
}

TrajectoryPoint TrajectoryGenerator::StepOscillation() {
  if (stage_ == Stage::kLeadingRest) {
    if (rest_left_ > 0) {
      --rest_left_;
      position_ = neutral_;
      return {neutral_, AngularVelocity{}, Segment::kRest, 0, false};
    }
    stage_ = Stage::kCycling;
  }
  if (stage_ == Stage::kCycling) {
    const std::uint32_t phase = (quadrant_ << 30) | phase_offset_;
    const auto [sine, cosine] = SinCos(phase);
    // No saturation on this path. |sin|, |cos| <= 1 (2^30 raw), so each rounded
    // product is at most its other factor in magnitude: A <= kMaxTrajectoryAmplitude,
    // and validation bounded neutral ± A to Angle's range and the peak velocity plus
    // |dA/dt| to AngularVelocity's (ValidateOscillation; both ramps stay between their
    // validated ends).
    const auto position =
        Angle::FromRaw(neutral_.raw() +
                       MulInRange<Angle>(Angle::FromRaw(amplitude_.value()), sine).raw());
    const auto peak = AngularVelocity::FromRaw(peak_velocity_.value());
    const AngularVelocity velocity =
        ramping_ ? AngularVelocity::FromRaw(
                       MulInRange<AngularVelocity>(peak, cosine).raw() +
                       MulInRange<AngularVelocity>(amplitude_rate_, sine).raw())
                 : MulInRange<AngularVelocity>(peak, cosine);
    const TrajectoryPoint point{position, velocity, kQuadrantSegment[quadrant_],
                                repetition_, false};
    AdvanceCycle();
    position_ = point.position;
    return point;
  }
  // Trailing rest.
  position_ = neutral_;
  if (rest_left_ > 0) {
    --rest_left_;
    return {neutral_, AngularVelocity{}, Segment::kRest, repetition_, false};
  }
  mode_ = TrajectoryMode::kIdle;  // repetition_ stays at the count completed
  return {neutral_, AngularVelocity{}, Segment::kIdle, repetition_, true};
}

// Inlined: one call fewer each tick (see Step in the header for what it saved).
[[gnu::always_inline]] inline void TrajectoryGenerator::AdvanceCycle() {
  if (ramping_) {  // a sine's amplitude is constant: nothing to advance
    amplitude_.Advance();
    peak_velocity_.Advance();
  }
  if (++tick_in_quarter_ < quarter_ticks_) {
    // phase_offset_ = floor(tick_in_quarter_·2^30 / Q), kept exact by the remainder.
    phase_offset_ += phase_step_;
    phase_accumulator_ += phase_remainder_;
    if (phase_accumulator_ >= quarter_ticks_) {
      phase_accumulator_ -= quarter_ticks_;
      ++phase_offset_;
    }
    return;
  }
  // A quarter turn ends: restart the quarter exactly at the next multiple of 2^30.
  tick_in_quarter_ = 0;
  phase_offset_ = 0;
  phase_accumulator_ = 0;
  if (++quadrant_ < 4) return;
  quadrant_ = 0;
  if (++repetition_ == repetitions_) {
    stage_ = Stage::kTrailingRest;
    rest_left_ = rest_ticks_;
  }
}

TrajectoryPoint TrajectoryGenerator::StepStream() {
  const std::int64_t error = std::int64_t{target_.raw()} - position_.raw();
  std::int64_t step = error;
  if (step > max_step_) step = max_step_;
  if (step < -std::int64_t{max_step_}) step = -std::int64_t{max_step_};
  // Between the old position and the target, so inside Angle's range.
  position_ = Angle::FromRaw(static_cast<std::int32_t>(position_.raw() + step));
  const auto velocity = FixedCast<AngularVelocity>(
      WideAngularVelocity::FromRaw(step * static_cast<std::int64_t>(tick_rate_hz_)));
  return {position_, velocity, Segment::kStream, 0, false};
}

}  // namespace mjc
