// Motor quadrature extension and joint-frame decoding against independent references:
// the extended count against a plain int64 sum of the true steps, angles against double
// arithmetic from the config's own numbers, frame status against a bit-by-bit count of
// the 16-bit word. These vectors run on the host and on the Cortex-M4 under QEMU.
//
// Error bounds, in Angle LSB (2^-24 rad):
//   motor θ_m: <= 0.5 + 0.25 / s, s = the scale in LSB a count (0.5005 for 2048 counts
//              at 100:1; 0.749 at the finest legal resolution), or saturated exactly;
//   joint θ_j: <= 0.5 for every count, offset and direction.
// The double reference's own rounding adds at most 2^-50 of the value (below 1e-6 LSB
// here), which the checks allow for.
#include <cstdint>
#include <limits>
#include <numbers>

#include "mjc/core/encoder.h"
#include "mjc/core/quantities.h"
#include "vector_test.h"

namespace {

using mjc::Angle;
using mjc::JointEncoderConfig;
using mjc::JointFrameStatus;
using mjc::MotorEncoder;
using mjc::MotorEncoderConfig;
using mjc::MotorEncoderConfigError;
using mjc::MotorEncoderState;
using mjc::vt::Rng;

constexpr double kLsbPerRad = 16777216.0;  // 2^24
constexpr double kAngleMaxLsb = 2147483647.0;
constexpr double kAngleMinLsb = -2147483648.0;

double AbsD(double x) { return x < 0 ? -x : x; }

// The timer register for a true position: the low 16 bits, as the hardware counts.
std::uint16_t TimerCount(std::int64_t position) {
  return static_cast<std::uint16_t>(static_cast<std::uint64_t>(position) & 0xFFFFu);
}

// floor(x / 65536) for signed x, without relying on shifts of negative values.
std::int64_t WrapIndex(std::int64_t x) {
  return x >= 0 ? x / 65536 : -((-x + 65535) / 65536);
}

// ----- Motor encoder: reference conversion ---------------------------------------------

// Angle LSB per count, from the config in double.
double ReferenceLsbPerCount(const MotorEncoderConfig& c) {
  return 2.0 * std::numbers::pi * kLsbPerRad * static_cast<double>(c.gear_denominator) /
         (static_cast<double>(c.counts_per_rev) * static_cast<double>(c.gear_numerator));
}

// θ_m in LSB (unsaturated) for an extended count.
double ReferenceMotorLsb(const MotorEncoderConfig& c, std::int64_t extended) {
  const double counts = static_cast<double>(extended - c.zero_offset_counts);
  return static_cast<double>(c.direction) * counts * ReferenceLsbPerCount(c);
}

double Saturate(double lsb) {
  return lsb > kAngleMaxLsb ? kAngleMaxLsb : (lsb < kAngleMinLsb ? kAngleMinLsb : lsb);
}

// The documented bound, plus the double reference's own rounding.
double MotorBoundLsb(const MotorEncoderConfig& c, double ref_lsb) {
  return 0.5 + 0.25 / ReferenceLsbPerCount(c) + AbsD(ref_lsb) * 1e-15;
}

// ----- Quadrature extension ------------------------------------------------------------

MJC_VECTOR_TEST(QuadratureExtension, RandomWalksOverHundredsOfWrapsLoseNothing) {
  // Setup: a walk that alternates drifting runs (all steps one way, to cross many wraps)
  // with unbiased runs, every step in [-32767, 32767], starting near the top of the
  // timer's range.
  const MotorEncoderConfig config;
  MotorEncoderState state;
  MotorEncoder encoder(&config, &state);
  Rng rng(0xE1C0DE01);
  std::int64_t truth = 65000;
  encoder.Reset(TimerCount(truth));

  int extended_mismatches = 0;
  int step_mismatches = 0;
  int low_bits_mismatches = 0;
  std::int64_t wraps = 0;
  std::int64_t max_step = 0;
  std::int64_t min_step = 0;
  std::int64_t max_truth = truth;
  std::int64_t min_truth = truth;
  // Runs of ~24.6 M counts (375 wraps) each: up, back, unbiased, down, back, unbiased.
  constexpr int kBias[] = {1, -1, 0, -1, 1, 0};
  for (int run = 0; run < 60; ++run) {
    const int bias = kBias[run % 6];
    for (int i = 0; i < 1500; ++i) {
      std::int64_t step = 0;
      if (bias == 0) {
        step = rng.NextI32() % 32768;  // [-32767, 32767]
      } else {
        step = bias * static_cast<std::int64_t>(rng.Next() % 32768u);
      }
      // Exercise: one sample of the timer.
      const std::int64_t before = truth;
      truth += step;
      encoder.Update(TimerCount(truth));
      // Verify against the plain int64 sum.
      if (encoder.extended_count() != truth) ++extended_mismatches;
      if (state.last_step_counts != step) ++step_mismatches;
      if (TimerCount(state.extended_count) != state.last_count) ++low_bits_mismatches;
      wraps += WrapIndex(truth) > WrapIndex(before)
                   ? WrapIndex(truth) - WrapIndex(before)
                   : WrapIndex(before) - WrapIndex(truth);
      max_step = step > max_step ? step : max_step;
      min_step = step < min_step ? step : min_step;
      max_truth = truth > max_truth ? truth : max_truth;
      min_truth = truth < min_truth ? truth : min_truth;
    }
  }
  VT_EXPECT_EQ(extended_mismatches, 0);
  VT_EXPECT_EQ(step_mismatches, 0);
  VT_EXPECT_EQ(low_bits_mismatches, 0);
  VT_EXPECT_EQ(encoder.extended_count(), truth);
  // The walk is the one intended: hundreds of wraps, both directions, near-full steps,
  // and far beyond the 16-bit range on both sides of zero.
  VT_EXPECT_TRUE(wraps > 10000);
  VT_EXPECT_TRUE(max_step > 32700 && min_step < -32700);
  VT_EXPECT_TRUE(max_truth > 200 * 65536);
  VT_EXPECT_TRUE(min_truth < -200 * 65536);
}

MJC_VECTOR_TEST(QuadratureExtension, ExtremeStepsAndTheAliasingLimit) {
  const MotorEncoderConfig config;
  MotorEncoderState state;
  MotorEncoder encoder(&config, &state);
  encoder.Reset(65535);
  VT_EXPECT_EQ(encoder.extended_count(), 65535);
  VT_EXPECT_EQ(state.last_step_counts, 0);

  // The largest steps each way, across the wrap, are read exactly.
  std::int64_t truth = 65535;
  const std::int64_t steps[] = {32767,  32767, 32767, -32768, -32768, -32768,
                                -32768, 1,     -1,    -32767, 32767,  0};
  for (std::int64_t step : steps) {
    truth += step;
    encoder.Update(TimerCount(truth));
    VT_EXPECT_EQ(encoder.extended_count(), truth);
    VT_EXPECT_EQ(state.last_step_counts, step);
  }

  // One more count than half the range aliases: +32768 reads as -32768, so the motor
  // must move fewer than 32768 counts a sample (the documented limit).
  truth += 32768;
  encoder.Update(TimerCount(truth));
  VT_EXPECT_EQ(state.last_step_counts, -32768);
  VT_EXPECT_EQ(encoder.extended_count(), truth - 65536);
}

MJC_VECTOR_TEST(QuadratureExtension, ClearedStateStartsAtTimerZero) {
  const MotorEncoderConfig config;
  MotorEncoderState state;
  state.extended_count = 12345;
  state.last_count = 7;
  state.angle = Angle::Max();
  state.angle_saturated = true;
  state.Clear();
  VT_EXPECT_EQ(state.extended_count, 0);
  VT_EXPECT_EQ(static_cast<int>(state.last_count), 0);
  VT_EXPECT_EQ(state.angle.raw(), 0);
  VT_EXPECT_TRUE(!state.angle_saturated);
  // Without Reset, the first sample is taken relative to timer count 0 (power-on).
  MotorEncoder encoder(&config, &state);
  encoder.Update(65534);
  VT_EXPECT_EQ(encoder.extended_count(), -2);
}

// ----- Motor encoder: angle conversion -------------------------------------------------

// Configs spanning the legal resolution range.
const MotorEncoderConfig kMotorConfigs[] = {
    {2048, 100, 1, 1, 0},              // the design point: 514.7 LSB a count
    {2048, 3249, 65, 1, 0},            // a rational planetary ratio, 1029.8 LSB a count
    {2048, 3249, 65, -1, -777777},     // reversed, offset
    {4096, 1, 1, -1, 1000},            // direct drive, 25,736 LSB a count
    {1 << 20, 100, 1, 1, 0},           // finest legal: 1.0053 LSB a count
    {7, 1, 1, 1, 3},                   // coarsest legal: 0.898 rad a count
    {2000, 19, 1, 1, -1234567890123},  // offset far beyond the int32 range
};

MJC_VECTOR_TEST(MotorEncoderAngle, WithinBoundOfDoubleReference) {
  Rng rng(0xE1C0DE02);
  double worst_excess = -1.0;  // max over samples of (error - bound); must be <= 0
  int checked = 0;
  for (const MotorEncoderConfig& config : kMotorConfigs) {
    MotorEncoderState state;
    const MotorEncoder encoder(&config, &state);
    VT_EXPECT_TRUE(encoder.config_error() == MotorEncoderConfigError::kOk);
    // Counts across the unsaturated range, ±(2^31 / s) counts about the offset.
    const double half_span = kAngleMaxLsb / ReferenceLsbPerCount(config);
    for (int i = 0; i < 4000; ++i) {
      const double u = static_cast<double>(rng.NextI32()) / 2147483648.0;  // [-1, 1)
      const std::int64_t c =
          static_cast<std::int64_t>(u * half_span * ((i & 1) ? 1.0 : 0.001));
      const std::int64_t extended = config.zero_offset_counts + c;
      const double ref = ReferenceMotorLsb(config, extended);
      if (ref >= kAngleMaxLsb || ref <= kAngleMinLsb) continue;
      const double got = static_cast<double>(encoder.CountToAngle(extended).raw());
      const double excess = AbsD(got - ref) - MotorBoundLsb(config, ref);
      worst_excess = excess > worst_excess ? excess : worst_excess;
      ++checked;
    }
  }
  VT_EXPECT_LE(worst_excess, 0.0);
  VT_EXPECT_TRUE(checked > 20000);
}

MJC_VECTOR_TEST(MotorEncoderAngle, DesignPointIsWithinHalfLsbAndOneTurnIsTwoPi) {
  // 2048 counts, 100:1: 204,800 counts a pulley revolution.
  const MotorEncoderConfig config{2048, 100, 1, 1, 0};
  MotorEncoderState state;
  MotorEncoder encoder(&config, &state);
  VT_EXPECT_EQ(encoder.CountToAngle(204800).raw(), 105414357);  // round(2π · 2^24)
  VT_EXPECT_EQ(encoder.CountToAngle(-204800).raw(), -105414357);
  VT_EXPECT_EQ(encoder.CountToAngle(0).raw(), 0);
  VT_EXPECT_EQ(encoder.CountToAngle(1).raw(), 515);  // 514.72
  VT_EXPECT_EQ(encoder.CountToAngle(-1).raw(), -515);
  double worst = 0;
  for (std::int64_t c = -4172151; c <= 4172151; c += 997) {
    const double err = AbsD(static_cast<double>(encoder.CountToAngle(c).raw()) -
                            ReferenceMotorLsb(config, c));
    worst = err > worst ? err : worst;
  }
  VT_EXPECT_LE(worst, 0.5005);
}

MJC_VECTOR_TEST(MotorEncoderAngle, UpdateFollowsTheWalkInAngleToo) {
  const MotorEncoderConfig config{2048, 3249, 65, -1, 40000};
  MotorEncoderState state;
  MotorEncoder encoder(&config, &state);
  Rng rng(0xE1C0DE03);
  std::int64_t truth = 40000;
  encoder.Reset(TimerCount(truth));
  VT_EXPECT_EQ(state.angle.raw(), 0);
  double worst_excess = -1.0;
  for (int i = 0; i < 20000; ++i) {
    truth += rng.NextI32() % 4096;
    const Angle got = encoder.Update(TimerCount(truth));
    VT_EXPECT_TRUE(got == state.angle);
    const double ref = ReferenceMotorLsb(config, truth);
    const double excess =
        AbsD(static_cast<double>(got.raw()) - Saturate(ref)) - MotorBoundLsb(config, ref);
    worst_excess = excess > worst_excess ? excess : worst_excess;
  }
  VT_EXPECT_LE(worst_excess, 0.0);
}

MJC_VECTOR_TEST(MotorEncoderAngle, DirectionAndZeroOffset) {
  const MotorEncoderConfig forward{2048, 100, 1, 1, 5000};
  const MotorEncoderConfig reverse{2048, 100, 1, -1, 5000};
  MotorEncoderState fs;
  MotorEncoderState rs;
  MotorEncoder f(&forward, &fs);
  MotorEncoder r(&reverse, &rs);
  // The offset is where the angle is zero.
  VT_EXPECT_EQ(f.CountToAngle(5000).raw(), 0);
  VT_EXPECT_EQ(r.CountToAngle(5000).raw(), 0);
  // A quarter pulley turn above the offset is +π/2 forward and -π/2 reversed.
  const std::int64_t quarter = 5000 + 51200;
  VT_EXPECT_EQ(f.CountToAngle(quarter).raw(),
               Angle::Quantize(std::numbers::pi / 2).raw());
  VT_EXPECT_EQ(r.CountToAngle(quarter).raw(),
               Angle::Quantize(-std::numbers::pi / 2).raw());
  // Through Reset/Update as well.
  f.Reset(TimerCount(5000));
  r.Reset(TimerCount(5000));
  VT_EXPECT_EQ(fs.angle.raw(), 0);
  // Two samples: a 51,200-count step at once would alias (limit 32,767).
  const std::int64_t positions[] = {5000 - 25600, 5000 - 51200};
  for (std::int64_t position : positions) {
    f.Update(TimerCount(position));
    r.Update(TimerCount(position));
  }
  VT_EXPECT_EQ(f.extended_count(), 5000 - 51200);
  VT_EXPECT_EQ(fs.angle.raw(), Angle::Quantize(-std::numbers::pi / 2).raw());
  VT_EXPECT_EQ(rs.angle.raw(), Angle::Quantize(std::numbers::pi / 2).raw());
}

MJC_VECTOR_TEST(MotorEncoderAngle, SaturatesBeyondRangeAndRecovers) {
  // 2048 counts at 100:1: ±128 rad is ±4,172,151 counts (2^31 / 514.72).
  const MotorEncoderConfig config{2048, 100, 1, 1, 0};
  MotorEncoderState state;
  MotorEncoder encoder(&config, &state);
  encoder.Reset(0);
  std::int64_t truth = 0;
  int wrong_saturation = 0;
  int wrong_angle = 0;
  int saturated_samples = 0;
  // Out to +5e6 counts, down to -5e6, back to 0, in steps of 25,000.
  const std::int64_t legs[][2] = {{200, 25000}, {400, -25000}, {200, 25000}};
  for (const auto& leg : legs) {
    for (std::int64_t i = 0; i < leg[0]; ++i) {
      truth += leg[1];
      encoder.Update(TimerCount(truth));
      const double ref = ReferenceMotorLsb(config, truth);
      const bool beyond = ref >= kAngleMaxLsb || ref <= kAngleMinLsb;
      if (beyond) {
        ++saturated_samples;
        if (state.angle != (ref > 0 ? Angle::Max() : Angle::Min())) ++wrong_angle;
      } else if (AbsD(static_cast<double>(state.angle.raw()) - ref) >
                 MotorBoundLsb(config, ref)) {
        ++wrong_angle;
      }
      if (state.angle_saturated != beyond) ++wrong_saturation;
    }
  }
  VT_EXPECT_EQ(wrong_angle, 0);
  VT_EXPECT_EQ(wrong_saturation, 0);
  VT_EXPECT_TRUE(saturated_samples > 100);
  VT_EXPECT_EQ(encoder.extended_count(), 0);
  VT_EXPECT_EQ(state.angle.raw(), 0);

  // The edge: the last count inside the range, the first outside.
  VT_EXPECT_TRUE(encoder.CountToAngle(4172151) < Angle::Max());
  VT_EXPECT_TRUE(encoder.CountToAngle(4172152) == Angle::Max());
  VT_EXPECT_TRUE(encoder.CountToAngle(-4172151) > Angle::Min());
  VT_EXPECT_TRUE(encoder.CountToAngle(-4172153) == Angle::Min());
  // The int64 extremes saturate too, including through an extreme offset and reversal.
  constexpr std::int64_t kMax = std::numeric_limits<std::int64_t>::max();
  constexpr std::int64_t kMin = std::numeric_limits<std::int64_t>::min();
  VT_EXPECT_TRUE(encoder.CountToAngle(kMax) == Angle::Max());
  VT_EXPECT_TRUE(encoder.CountToAngle(kMin) == Angle::Min());
  const MotorEncoderConfig far{2048, 100, 1, -1, kMin};
  MotorEncoderState far_state;
  const MotorEncoder far_encoder(&far, &far_state);
  VT_EXPECT_TRUE(far_encoder.CountToAngle(kMax) == Angle::Min());
  VT_EXPECT_TRUE(far_encoder.CountToAngle(0) == Angle::Min());
  VT_EXPECT_TRUE(far_encoder.CountToAngle(kMin) == Angle{});
}

MJC_VECTOR_TEST(MotorEncoderConfig, ValidationErrorsAreStable) {
  VT_EXPECT_EQ(static_cast<int>(MotorEncoderConfigError::kOk), 0);
  VT_EXPECT_EQ(static_cast<int>(MotorEncoderConfigError::kCountsPerRevNotPositive), 1);
  VT_EXPECT_EQ(static_cast<int>(MotorEncoderConfigError::kGearRatioNotPositive), 2);
  VT_EXPECT_EQ(static_cast<int>(MotorEncoderConfigError::kDirectionInvalid), 3);
  VT_EXPECT_EQ(static_cast<int>(MotorEncoderConfigError::kResolutionOutOfRange), 4);

  struct Case {
    MotorEncoderConfig config;
    MotorEncoderConfigError want;
  };
  const Case cases[] = {
      {{2048, 100, 1, 1, 0}, MotorEncoderConfigError::kOk},
      {{0, 100, 1, 1, 0}, MotorEncoderConfigError::kCountsPerRevNotPositive},
      {{-2048, 100, 1, 1, 0}, MotorEncoderConfigError::kCountsPerRevNotPositive},
      {{2048, 0, 1, 1, 0}, MotorEncoderConfigError::kGearRatioNotPositive},
      {{2048, 100, -1, 1, 0}, MotorEncoderConfigError::kGearRatioNotPositive},
      {{2048, 100, 1, 0, 0}, MotorEncoderConfigError::kDirectionInvalid},
      {{2048, 100, 1, 2, 0}, MotorEncoderConfigError::kDirectionInvalid},
      // 2^20 · 101 counts a pulley revolution: finer than 1 LSB (2π · 2^24 = 1.054e8).
      {{1 << 20, 101, 1, 1, 0}, MotorEncoderConfigError::kResolutionOutOfRange},
      {{1 << 20, 100, 1, 1, 0}, MotorEncoderConfigError::kOk},
      // 6 counts a pulley revolution: coarser than 1 rad a count.
      {{6, 1, 1, 1, 0}, MotorEncoderConfigError::kResolutionOutOfRange},
      {{7, 1, 1, 1, 0}, MotorEncoderConfigError::kOk},
      {{2147483647, 2147483647, 1, 1, 0}, MotorEncoderConfigError::kResolutionOutOfRange},
      {{1, 1, 2147483647, 1, 0}, MotorEncoderConfigError::kResolutionOutOfRange},
      // A 95-bit numerator in the scale's division: 1/100 of a full-range count.
      {{2147483647, 100, 2147483647, 1, 0}, MotorEncoderConfigError::kOk},
  };
  for (const Case& c : cases) {
    VT_EXPECT_EQ(static_cast<int>(mjc::ValidateMotorEncoderConfig(c.config)),
                 static_cast<int>(c.want));
    mjc::MotorEncoderScale scale;
    scale.count_limit = 99;
    const MotorEncoderConfigError e = mjc::ComputeMotorEncoderScale(c.config, &scale);
    VT_EXPECT_EQ(static_cast<int>(e), static_cast<int>(c.want));
    if (e != MotorEncoderConfigError::kOk) {
      VT_EXPECT_EQ(scale.lsb_per_count_q32, 0);
      VT_EXPECT_EQ(scale.count_limit, 0);
    }
  }
}

MJC_VECTOR_TEST(MotorEncoderConfig, ScaleMatchesDoubleWithinItsResolution) {
  for (const MotorEncoderConfig& config : kMotorConfigs) {
    mjc::MotorEncoderScale scale;
    VT_EXPECT_TRUE(mjc::ComputeMotorEncoderScale(config, &scale) ==
                   MotorEncoderConfigError::kOk);
    const double want_q32 = ReferenceLsbPerCount(config) * 4294967296.0;
    // Rounded to nearest: 0.5 in Q32, plus double's own 2^-52 relative.
    VT_EXPECT_LE(AbsD(static_cast<double>(scale.lsb_per_count_q32) - want_q32),
                 0.5 + want_q32 * 2.3e-16);
    // count_limit is the largest |c| with |c| · scale <= 2^63 - 1.
    const double product = static_cast<double>(scale.count_limit) *
                           static_cast<double>(scale.lsb_per_count_q32);
    VT_EXPECT_TRUE(product <= 9223372036854775807.0);
    VT_EXPECT_TRUE(product + static_cast<double>(scale.lsb_per_count_q32) >
                   9223372036854775807.0 * (1 - 1e-15));
  }
}

MJC_VECTOR_TEST(MotorEncoderConfig, InvalidConfigGivesZeroAngleUntilReconfigured) {
  MotorEncoderConfig config{2048, 100, 1, 0, 0};  // direction 0: invalid
  MotorEncoderState state;
  MotorEncoder encoder(&config, &state);
  VT_EXPECT_TRUE(encoder.config_error() == MotorEncoderConfigError::kDirectionInvalid);
  encoder.Reset(100);
  encoder.Update(30000);
  // Counts are still extended; the angle is withheld.
  VT_EXPECT_EQ(encoder.extended_count(), 30000);
  VT_EXPECT_EQ(state.angle.raw(), 0);
  VT_EXPECT_TRUE(!state.angle_saturated);
  config.direction = -1;
  VT_EXPECT_TRUE(encoder.Reconfigure() == MotorEncoderConfigError::kOk);
  VT_EXPECT_EQ(state.angle.raw(),
               Angle::Quantize(-30000 * 2.0 * std::numbers::pi / 204800.0).raw());
}

// ----- Joint encoder -------------------------------------------------------------------

// Number of 1 bits, by testing each bit in turn.
int OnesIn(std::uint16_t word) {
  int n = 0;
  for (int b = 0; b < 16; ++b) n += (word >> b) & 1;
  return n;
}

// θ_j in LSB for a count, from plain integer wrap-around and double.
double ReferenceJointLsb(int count, int offset, int direction) {
  int d = (count - offset) % 16384;
  if (d < 0) d += 16384;
  if (d >= 8192) d -= 16384;
  return static_cast<double>(direction * d) * (2.0 * std::numbers::pi / 16384.0) *
         kLsbPerRad;
}

MJC_VECTOR_TEST(JointFrame, StatusNumbersAreStable) {
  VT_EXPECT_EQ(static_cast<int>(JointFrameStatus::kOk), 0);
  VT_EXPECT_EQ(static_cast<int>(JointFrameStatus::kParityError), 1);
  VT_EXPECT_EQ(static_cast<int>(JointFrameStatus::kErrorFlag), 2);
  VT_EXPECT_EQ(static_cast<int>(mjc::JointEncoderConfigError::kOk), 0);
  VT_EXPECT_EQ(static_cast<int>(mjc::JointEncoderConfigError::kZeroOffsetOutOfRange), 1);
  VT_EXPECT_EQ(static_cast<int>(mjc::JointEncoderConfigError::kDirectionInvalid), 2);
}

MJC_VECTOR_TEST(JointFrame, EveryFrameClassifiedByBitCount) {
  // All 65,536 words: odd weight is a parity error whatever EF says; even weight with
  // bit 14 set is an error flag; the rest carry bits 13..0 as the count.
  const JointEncoderConfig config{0, 1};
  int wrong = 0;
  for (std::uint32_t w = 0; w < 65536; ++w) {
    const auto frame = static_cast<std::uint16_t>(w);
    const mjc::JointSample s = mjc::DecodeJointFrame(frame, config);
    const bool odd = (OnesIn(frame) % 2) != 0;
    const bool ef = ((w >> 14) & 1u) != 0;
    if (odd) {
      if (s.status != JointFrameStatus::kParityError) ++wrong;
    } else if (ef) {
      if (s.status != JointFrameStatus::kErrorFlag) ++wrong;
    } else {
      if (s.status != JointFrameStatus::kOk || s.count != (w & 0x3FFFu)) ++wrong;
    }
    // A frame that is not kOk yields neither count nor angle.
    if (s.status != JointFrameStatus::kOk && (s.count != 0 || s.angle != Angle{})) {
      ++wrong;
    }
  }
  VT_EXPECT_EQ(wrong, 0);
}

MJC_VECTOR_TEST(JointFrame, EncodedFramesAreValidAndEverySingleBitFlipIsCaught) {
  const JointEncoderConfig config{0, 1};
  int bad_encoding = 0;
  int undetected = 0;
  for (int count = 0; count < 16384; ++count) {
    for (int ef = 0; ef < 2; ++ef) {
      const std::uint16_t frame =
          mjc::EncodeJointFrame(static_cast<std::uint16_t>(count), ef != 0);
      // The frame holds exactly the count and the flag, with even weight.
      if ((frame & 0x3FFF) != count || ((frame >> 14) & 1) != ef ||
          OnesIn(frame) % 2 != 0) {
        ++bad_encoding;
      }
      const mjc::JointSample s = mjc::DecodeJointFrame(frame, config);
      const JointFrameStatus want =
          ef ? JointFrameStatus::kErrorFlag : JointFrameStatus::kOk;
      if (s.status != want) ++bad_encoding;
      for (int bit = 0; bit < 16; ++bit) {
        const auto flipped = static_cast<std::uint16_t>(frame ^ (1u << bit));
        if (mjc::DecodeJointFrame(flipped, config).status !=
            JointFrameStatus::kParityError) {
          ++undetected;
        }
      }
    }
  }
  VT_EXPECT_EQ(bad_encoding, 0);
  VT_EXPECT_EQ(undetected, 0);
  // Bits above 13 of the count argument are dropped, not folded into EF or parity.
  VT_EXPECT_EQ(mjc::EncodeJointFrame(0xC001, false),
               mjc::EncodeJointFrame(0x0001, false));
  // Parity is one bit: two flipped data bits pass it with a wrong count. Catching that
  // is the supervisor's plausibility check, not the frame's.
  const std::uint16_t two_flips =
      static_cast<std::uint16_t>(mjc::EncodeJointFrame(1000, false) ^ 0x0003u);
  const mjc::JointSample s = mjc::DecodeJointFrame(two_flips, config);
  VT_EXPECT_TRUE(s.status == JointFrameStatus::kOk);
  VT_EXPECT_EQ(s.count, 1003);
}

MJC_VECTOR_TEST(JointFrame, ErrorFlagWithGoodParityYieldsNoAngle) {
  const JointEncoderConfig config{100, 1};
  const mjc::JointSample s =
      mjc::DecodeJointFrame(mjc::EncodeJointFrame(5000, true), config);
  VT_EXPECT_TRUE(s.status == JointFrameStatus::kErrorFlag);
  VT_EXPECT_EQ(s.count, 0);
  VT_EXPECT_EQ(s.angle.raw(), 0);
  // Hand-built frames: 0x4000 has one 1 bit (parity error, EF not trusted); 0xC000 has
  // two (EF); 0x8001 has two (count 1, EF clear).
  VT_EXPECT_TRUE(mjc::DecodeJointFrame(0x4000, config).status ==
                 JointFrameStatus::kParityError);
  VT_EXPECT_TRUE(mjc::DecodeJointFrame(0xC000, config).status ==
                 JointFrameStatus::kErrorFlag);
  const mjc::JointSample one = mjc::DecodeJointFrame(0x8001, JointEncoderConfig{0, 1});
  VT_EXPECT_TRUE(one.status == JointFrameStatus::kOk);
  VT_EXPECT_EQ(one.count, 1);
  VT_EXPECT_EQ(one.angle.raw(), 6434);  // 2π/16384 rad = 6433.98 LSB
  VT_EXPECT_EQ(mjc::EncodeJointFrame(1, false), 0x8001);
  VT_EXPECT_EQ(mjc::EncodeJointFrame(3, false), 0x0003);
  VT_EXPECT_EQ(mjc::EncodeJointFrame(0, true), 0xC000);
}

MJC_VECTOR_TEST(JointAngle, AllCountsWithinHalfLsbOfDouble) {
  const int offsets[] = {0, 8192, 16000, 16383};
  double worst = 0;
  int out_of_range = 0;
  for (int offset : offsets) {
    for (int direction = -1; direction <= 1; direction += 2) {
      const JointEncoderConfig config{static_cast<std::uint16_t>(offset),
                                      static_cast<std::int8_t>(direction)};
      for (int count = 0; count < 16384; ++count) {
        const double ref = ReferenceJointLsb(count, offset, direction);
        const mjc::JointSample s = mjc::DecodeJointFrame(
            mjc::EncodeJointFrame(static_cast<std::uint16_t>(count), false), config);
        const double err = AbsD(static_cast<double>(s.angle.raw()) - ref);
        worst = err > worst ? err : worst;
        // [-π, π) forward, (-π, π] reversed.
        const double pi_lsb = std::numbers::pi * kLsbPerRad;
        const double a = static_cast<double>(s.angle.raw());
        if (direction > 0 ? (a < -pi_lsb - 0.5 || a >= pi_lsb - 0.5)
                          : (a <= -pi_lsb + 0.5 || a > pi_lsb + 0.5)) {
          ++out_of_range;
        }
      }
    }
  }
  VT_EXPECT_LE(worst, 0.5 + 1e-6);
  VT_EXPECT_EQ(out_of_range, 0);
}

MJC_VECTOR_TEST(JointAngle, ZeroOffsetWrapsAround) {
  // Offset 16000, count 100: (100 - 16000) mod 16384 = 484 counts past zero.
  const JointEncoderConfig forward{16000, 1};
  const JointEncoderConfig reverse{16000, -1};
  const double step = 2.0 * std::numbers::pi / 16384.0;
  VT_EXPECT_EQ(mjc::JointCountToAngle(100, forward).raw(),
               Angle::Quantize(484 * step).raw());
  VT_EXPECT_EQ(mjc::JointCountToAngle(100, reverse).raw(),
               Angle::Quantize(-484 * step).raw());
  // Just below the offset is a small negative angle, not nearly a full turn.
  VT_EXPECT_EQ(mjc::JointCountToAngle(15999, forward).raw(),
               Angle::Quantize(-step).raw());
  // Half a turn away is -π forward (the range's closed end) and +π reversed.
  const std::uint16_t half = (16000 + 8192) % 16384;
  VT_EXPECT_EQ(mjc::JointCountToAngle(half, forward).raw(),
               Angle::Quantize(-std::numbers::pi).raw());
  VT_EXPECT_EQ(mjc::JointCountToAngle(half, reverse).raw(),
               Angle::Quantize(std::numbers::pi).raw());
  // Bits above 13 of the count are ignored.
  VT_EXPECT_EQ(mjc::JointCountToAngle(100 | 0xC000, forward).raw(),
               mjc::JointCountToAngle(100, forward).raw());
}

MJC_VECTOR_TEST(JointEncoderConfig, ValidationAndLenientDecoding) {
  VT_EXPECT_TRUE(mjc::ValidateJointEncoderConfig({0, 1}) ==
                 mjc::JointEncoderConfigError::kOk);
  VT_EXPECT_TRUE(mjc::ValidateJointEncoderConfig({16383, -1}) ==
                 mjc::JointEncoderConfigError::kOk);
  VT_EXPECT_TRUE(mjc::ValidateJointEncoderConfig({16384, 1}) ==
                 mjc::JointEncoderConfigError::kZeroOffsetOutOfRange);
  VT_EXPECT_TRUE(mjc::ValidateJointEncoderConfig({0, 0}) ==
                 mjc::JointEncoderConfigError::kDirectionInvalid);
  VT_EXPECT_TRUE(mjc::ValidateJointEncoderConfig({0, -2}) ==
                 mjc::JointEncoderConfigError::kDirectionInvalid);
  // Decoding anyway: the offset's low 14 bits are used, a negative direction is -1 and
  // anything else +1.
  const std::uint16_t frame = mjc::EncodeJointFrame(300, false);
  VT_EXPECT_TRUE(mjc::DecodeJointFrame(frame, {16384 + 100, 1}).angle ==
                 mjc::DecodeJointFrame(frame, {100, 1}).angle);
  VT_EXPECT_TRUE(mjc::DecodeJointFrame(frame, {100, -5}).angle ==
                 mjc::DecodeJointFrame(frame, {100, -1}).angle);
  VT_EXPECT_TRUE(mjc::DecodeJointFrame(frame, {100, 0}).angle ==
                 mjc::DecodeJointFrame(frame, {100, 1}).angle);
  VT_EXPECT_EQ(mjc::DecodeJointFrame(frame, {100, -5}).angle.raw(),
               Angle::Quantize(-200 * 2.0 * std::numbers::pi / 16384.0).raw());
}

}  // namespace
