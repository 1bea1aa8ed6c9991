// Setpoint generators (mjc/core/trajectory.h) against references computed here: the
// timing (segment, repetition, done) by integer counting from the configuration, the
// setpoints by double arithmetic. These vectors run on the host and on the Cortex-M4
// under QEMU.
//
// Bounds, from trajectory.h (A the amplitude in rad, V = A·ω in rad/s):
//   sine position <= 0.5 + 0.038·A LSB of Angle; velocity <= 1 + 0.0024·V LSB of
//   AngularVelocity, both against the exact value at the generated tick;
//   the sweep adds <= 0.5 LSB per ramp: position <= 1.05, velocity <= 2.2 LSB;
//   stream steps never exceed max_rate·dt.
#include <array>
#include <cmath>
#include <cstdint>
#include <initializer_list>
#include <numbers>

#include "mjc/core/quantities.h"
#include "mjc/core/trajectory.h"
#include "vector_test.h"

namespace {

using mjc::Angle;
using mjc::AngularVelocity;
using mjc::Frequency;
using mjc::RampedSineConfig;
using mjc::Segment;
using mjc::SineConfig;
using mjc::TrajectoryError;
using mjc::TrajectoryGenerator;
using mjc::TrajectoryMode;
using mjc::TrajectoryPoint;
using mjc::vt::Rng;
using namespace mjc::literals;

constexpr double kAngleLsb = 1.0 / 16777216.0;    // 2^-24 rad
constexpr double kVelocityLsb = 1.0 / 1048576.0;  // 2^-20 rad/s
constexpr Segment kQuarterSegment[4] = {
    Segment::kFlexionLoading, Segment::kFlexionUnloading, Segment::kExtensionLoading,
    Segment::kExtensionUnloading};

static_assert(static_cast<int>(Segment::kIdle) == 0);
static_assert(static_cast<int>(Segment::kRest) == 1);
static_assert(static_cast<int>(Segment::kFlexionLoading) == 2);
static_assert(static_cast<int>(Segment::kFlexionUnloading) == 3);
static_assert(static_cast<int>(Segment::kExtensionLoading) == 4);
static_assert(static_cast<int>(Segment::kExtensionUnloading) == 5);
static_assert(static_cast<int>(Segment::kHold) == 6);
static_assert(static_cast<int>(Segment::kStream) == 7);
static_assert(static_cast<int>(TrajectoryError::kOk) == 0);
static_assert(static_cast<int>(TrajectoryError::kAmplitudeNotPositive) == 1);
static_assert(static_cast<int>(TrajectoryError::kAmplitudeTooLarge) == 2);
static_assert(static_cast<int>(TrajectoryError::kAmplitudeNegative) == 3);
static_assert(static_cast<int>(TrajectoryError::kSetpointOutOfRange) == 4);
static_assert(static_cast<int>(TrajectoryError::kVelocityOutOfRange) == 5);
static_assert(static_cast<int>(TrajectoryError::kFrequencyNotPositive) == 16);
static_assert(static_cast<int>(TrajectoryError::kFrequencyTooHigh) == 17);
static_assert(static_cast<int>(TrajectoryError::kZeroRepetitions) == 18);
static_assert(static_cast<int>(TrajectoryError::kRestTooLong) == 19);
static_assert(static_cast<int>(TrajectoryError::kTickRateOutOfRange) == 20);
static_assert(static_cast<int>(TrajectoryError::kTickRateMismatch) == 21);
static_assert(static_cast<int>(TrajectoryError::kRateNotPositive) == 32);
static_assert(static_cast<int>(TrajectoryError::kRateBelowResolution) == 33);
static_assert(static_cast<int>(TrajectoryError::kNotStreaming) == 34);

int Code(TrajectoryError e) { return static_cast<int>(e); }

// A trial's shape as the test derives it from the configuration, independently of the
// generator: rest and cycle lengths in ticks, amplitudes and neutral as doubles.
struct Trial {
  double neutral;
  double start_amplitude;
  double end_amplitude;
  std::int64_t rest;   // ticks
  std::int64_t cycle;  // ticks, N
  int repetitions;
  double tick_rate_hz;
};

// N = 4·round(f_tick / (4·f)), f as the Q15.16 value the configuration holds.
std::int64_t CycleTicks(Frequency f, double tick_rate_hz) {
  return 4 * std::llround(tick_rate_hz / (4.0 * f.ToDouble()));
}

// The shape of either configuration, its amplitude going from `start_amplitude` to
// `end_amplitude` over the cycles.
template <class Config>
Trial TrialOf(const Config& c, Angle start_amplitude, Angle end_amplitude) {
  const double tick = c.tick_rate_hz;
  return {c.neutral.ToDouble(),
          start_amplitude.ToDouble(),
          end_amplitude.ToDouble(),
          std::llround(c.rest_ms * tick / 1000.0),
          CycleTicks(c.frequency, tick),
          c.repetitions,
          tick};
}

Trial TrialOf(const SineConfig& c) { return TrialOf(c, c.amplitude, c.amplitude); }

Trial TrialOf(const RampedSineConfig& c) {
  return TrialOf(c, c.start_amplitude, c.end_amplitude);
}

struct Label {
  std::int64_t tick;
  Segment segment;
  int repetition;
  bool done;
  bool operator==(const Label&) const = default;
};

// The label of tick t (0 = the first Step() after the start), in closed form.
Label ExpectedLabel(const Trial& trial, std::int64_t t) {
  const std::int64_t cycling = trial.cycle * trial.repetitions;
  if (t < trial.rest) return {t, Segment::kRest, 0, false};
  const std::int64_t k = t - trial.rest;
  if (k < cycling) {
    const std::int64_t quarter = (k % trial.cycle) / (trial.cycle / 4);
    return {t, kQuarterSegment[quarter], static_cast<int>(k / trial.cycle), false};
  }
  if (k < cycling + trial.rest) return {t, Segment::kRest, trial.repetitions, false};
  return {t, Segment::kIdle, trial.repetitions, true};
}

constexpr int kMaxLabels = 64;
struct LabelList {
  std::array<Label, kMaxLabels> items{};
  int size = 0;
  void Push(const Label& l) {
    if (size < kMaxLabels) items[static_cast<std::size_t>(size)] = l;
    ++size;
  }
};

// The first tick of every segment (and of every repetition), listed by hand.
LabelList ExpectedTransitions(const Trial& trial) {
  LabelList list;
  const std::int64_t r = trial.rest;
  const std::int64_t n = trial.cycle;
  if (r > 0) list.Push({0, Segment::kRest, 0, false});
  for (int c = 0; c < trial.repetitions; ++c) {
    for (int q = 0; q < 4; ++q) {
      list.Push({r + c * n + q * n / 4, kQuarterSegment[q], c, false});
    }
  }
  const std::int64_t end = r + trial.repetitions * n;
  if (r > 0) list.Push({end, Segment::kRest, trial.repetitions, false});
  list.Push({end + r, Segment::kIdle, trial.repetitions, true});
  return list;
}

struct TrialResult {
  double position_lsb = 0;  // worst |position − reference|
  double velocity_lsb = 0;
  int label_mismatches = 0;
  int rest_mismatches = 0;  // rest / done ticks not exactly at neutral with velocity 0
  LabelList transitions;
};

// Steps a started generator through the whole trial plus `extra` ticks after it,
// comparing every tick with the closed-form label and the double reference
//   position = neutral + A(k)·sin(2πk/N),  velocity = A(k)·ω·cos(2πk/N) + A'·sin(2πk/N)
// with A(k) the linear ramp, ω = 2π·f_tick/N and A' = dA/dt.
TrialResult RunTrial(TrajectoryGenerator& generator, const Trial& trial,
                     std::int64_t extra = 100) {
  TrialResult result;
  const std::int64_t cycling = trial.cycle * trial.repetitions;
  const std::int64_t total = 2 * trial.rest + cycling + extra;
  const double omega =
      2.0 * std::numbers::pi * trial.tick_rate_hz / static_cast<double>(trial.cycle);
  const double delta = trial.end_amplitude - trial.start_amplitude;
  const double slope = delta * trial.tick_rate_hz / static_cast<double>(cycling);
  // sin / cos of 2πi/N by rotation, restarted at every cycle: 4 products a tick instead
  // of two library calls (soft-float on the Cortex-M4), drift < 1e-11 over a cycle.
  const double c1 = std::cos(2.0 * std::numbers::pi / static_cast<double>(trial.cycle));
  const double s1 = std::sin(2.0 * std::numbers::pi / static_cast<double>(trial.cycle));
  double s = 0;
  double c = 1;
  Label previous{-1, Segment::kIdle, -1, false};
  for (std::int64_t t = 0; t < total; ++t) {
    const TrajectoryPoint p = generator.Step();
    const Label got{t, p.segment, p.repetition, p.done};
    const Label want = ExpectedLabel(trial, t);
    if (!(got == want)) ++result.label_mismatches;
    if (got.segment != previous.segment || got.repetition != previous.repetition ||
        got.done != previous.done) {
      result.transitions.Push(got);
    }
    previous = got;

    const std::int64_t k = t - trial.rest;
    if (k < 0 || k >= cycling) {
      if (p.position.ToDouble() != trial.neutral || p.velocity.raw() != 0) {
        ++result.rest_mismatches;
      }
      continue;
    }
    if (k % trial.cycle == 0) {
      s = 0;
      c = 1;
    }
    const double amplitude = trial.start_amplitude + delta * static_cast<double>(k) /
                                                         static_cast<double>(cycling);
    const double position = trial.neutral + amplitude * s;
    const double velocity = amplitude * omega * c + slope * s;
    const double ep = std::fabs(p.position.ToDouble() - position) / kAngleLsb;
    const double ev = std::fabs(p.velocity.ToDouble() - velocity) / kVelocityLsb;
    result.position_lsb = ep > result.position_lsb ? ep : result.position_lsb;
    result.velocity_lsb = ev > result.velocity_lsb ? ev : result.velocity_lsb;
    const double next_s = s * c1 + c * s1;
    c = c * c1 - s * s1;
    s = next_s;
  }
  return result;
}

void ExpectTransitions(mjc::vt::Context& vt_context, const LabelList& got,
                       const LabelList& want) {
  VT_EXPECT_EQ(got.size, want.size);
  int mismatches = 0;
  for (int i = 0; i < got.size && i < want.size && i < kMaxLabels; ++i) {
    if (!(got.items[static_cast<std::size_t>(i)] ==
          want.items[static_cast<std::size_t>(i)])) {
      ++mismatches;
    }
  }
  VT_EXPECT_EQ(mismatches, 0);
}

// A whole run against the reference: the setpoints within `position_lsb` and
// `velocity_lsb` (the bounds of the file's head), every tick's label and every rest
// tick exact, and the first tick of every segment.
void ExpectReference(mjc::vt::Context& vt_context, const TrialResult& r,
                     const Trial& trial, double position_lsb, double velocity_lsb) {
  VT_EXPECT_LE(r.position_lsb, position_lsb);
  VT_EXPECT_LE(r.velocity_lsb, velocity_lsb);
  VT_EXPECT_EQ(r.label_mismatches, 0);
  VT_EXPECT_EQ(r.rest_mismatches, 0);
  ExpectTransitions(vt_context, r.transitions, ExpectedTransitions(trial));
}

// The paper's trial: 5 repetitions at 0.5 Hz, 3 s rest, 25° about a 0.2 rad neutral.
SineConfig PaperTrial() {
  SineConfig c;
  c.neutral = 0.2_rad;
  c.amplitude = 25.0_deg;
  c.frequency = 0.5_Hz;
  c.repetitions = 5;
  c.rest_ms = 3000;
  return c;
}

MJC_VECTOR_TEST(SineTrajectory, PaperTrialMatchesDoubleReference) {
  TrajectoryGenerator generator;
  const SineConfig config = PaperTrial();
  VT_EXPECT_EQ(Code(generator.StartSine(config)), Code(TrajectoryError::kOk));
  const Trial trial = TrialOf(config);
  VT_EXPECT_EQ(trial.cycle, 20000);  // 10 kHz / 0.5 Hz
  VT_EXPECT_EQ(trial.rest, 30000);
  VT_EXPECT_EQ(static_cast<std::int64_t>(generator.ticks_per_cycle()), trial.cycle);
  VT_EXPECT_EQ(static_cast<std::int64_t>(generator.rest_ticks()), trial.rest);

  const TrialResult r = RunTrial(generator, trial, 1000);
  // A = 0.436 rad, V = 1.37 rad/s: 0.517 and 1.003 LSB.
  ExpectReference(vt_context, r, trial, 0.55, 1.05);
  VT_EXPECT_EQ(r.transitions.size, 23);  // rest, 5 × 4 segments, rest, idle
  VT_EXPECT_TRUE(generator.mode() == TrajectoryMode::kIdle);
  VT_EXPECT_TRUE(generator.position() == config.neutral);
}

// Segment, repetition and done per tick, and the first tick of every segment, for
// frequencies whose cycle is not tick_rate/f (0.3 Hz -> 33,332 ticks), the fastest legal
// one (tick/4: 4 ticks a cycle), and without rest.
MJC_VECTOR_TEST(SineTrajectory, SegmentBoundariesAreTickExact) {
  struct Case {
    Frequency frequency;
    std::uint16_t repetitions;
    std::uint32_t rest_ms;
    Angle amplitude;
    std::int64_t cycle;  // N, worked out by hand
  };
  const Case cases[] = {
      {0.3_Hz, 2, 0, 10.0_deg, 33332},  // 19661/65536 Hz: 10^4/(4f) = 8333.25 -> 8333
      {2.5_Hz, 3, 100, 20.0_deg, 4000},
      {6.0_Hz, 4, 7, 6.0_deg, 1668},  // 10^4/(4·6) = 416.67 -> 417, rounded up
      {2500.0_Hz, 5, 1, 0.1_rad, 4},
  };
  for (const Case& k : cases) {
    SineConfig config;
    config.neutral = -0.1_rad;
    config.amplitude = k.amplitude;
    config.frequency = k.frequency;
    config.repetitions = k.repetitions;
    config.rest_ms = k.rest_ms;
    TrajectoryGenerator generator;
    VT_EXPECT_EQ(Code(generator.StartSine(config)), Code(TrajectoryError::kOk));
    const Trial trial = TrialOf(config);
    VT_EXPECT_EQ(trial.cycle, k.cycle);
    VT_EXPECT_EQ(static_cast<std::int64_t>(generator.ticks_per_cycle()), k.cycle);
    const TrialResult r = RunTrial(generator, trial);
    ExpectReference(vt_context, r, trial, 0.55, 1.05);
  }
}

// The commanded peak is the first unloading tick: exactly neutral + A with velocity 0,
// and the unique maximum of its cycle; the trough mirrors it; zero crossings are exact.
MJC_VECTOR_TEST(SineTrajectory, PeaksAndZerosOnQuarterTicks) {
  SineConfig config;
  config.neutral = -0.3_rad;
  config.amplitude = 25.0_deg;
  config.frequency = 2.5_Hz;  // 4000 ticks: neighbours of a peak differ by ~9 LSB
  config.repetitions = 3;
  config.rest_ms = 20;
  TrajectoryGenerator generator;
  VT_EXPECT_EQ(Code(generator.StartSine(config)), Code(TrajectoryError::kOk));
  constexpr std::int64_t kRest = 200;
  constexpr std::int64_t kCycle = 4000;
  const Angle high = config.neutral + config.amplitude;
  const Angle low = config.neutral - config.amplitude;
  for (int c = 0; c < 3; ++c) {
    std::int64_t argmax = -1;
    std::int64_t argmin = -1;
    int max_count = 0;
    int min_count = 0;
    Angle max = Angle::Min();
    Angle min = Angle::Max();
    for (std::int64_t t = 0; t < kCycle + (c == 0 ? kRest : 0); ++t) {
      const TrajectoryPoint p = generator.Step();
      const std::int64_t i = t - (c == 0 ? kRest : 0);  // tick within the cycle
      if (i < 0) continue;
      if (p.position > max) {
        max = p.position;
        argmax = i;
        max_count = 0;
      }
      if (p.position == max) ++max_count;
      if (p.position < min) {
        min = p.position;
        argmin = i;
        min_count = 0;
      }
      if (p.position == min) ++min_count;
      if (i == 0 || i == kCycle / 2) {
        VT_EXPECT_TRUE(p.position == config.neutral);
      }
      if (i == kCycle / 4 || i == 3 * kCycle / 4) {
        VT_EXPECT_EQ(p.velocity.raw(), 0);
      }
    }
    VT_EXPECT_EQ(argmax, kCycle / 4);
    VT_EXPECT_EQ(argmin, 3 * kCycle / 4);
    VT_EXPECT_EQ(max_count, 1);
    VT_EXPECT_EQ(min_count, 1);
    VT_EXPECT_TRUE(max == high);
    VT_EXPECT_TRUE(min == low);
  }
}

MJC_VECTOR_TEST(SineTrajectory, DoneHoldsNeutralUntilReplaced) {
  SineConfig config;
  config.neutral = 0.5_rad;
  config.amplitude = 8.0_deg;
  config.frequency = 5.0_Hz;  // 2000 ticks
  config.repetitions = 2;
  config.rest_ms = 0;
  TrajectoryGenerator generator;
  VT_EXPECT_EQ(Code(generator.StartSine(config)), Code(TrajectoryError::kOk));
  int done_ticks = 0;
  std::int64_t first_done = -1;
  for (std::int64_t t = 0; t < 6000; ++t) {
    const TrajectoryPoint p = generator.Step();
    if (p.done) {
      if (first_done < 0) first_done = t;
      ++done_ticks;
      VT_EXPECT_TRUE(p.position == config.neutral);
      VT_EXPECT_EQ(p.velocity.raw(), 0);
      VT_EXPECT_EQ(p.repetition, 2);
      VT_EXPECT_TRUE(p.segment == Segment::kIdle);
    }
  }
  VT_EXPECT_EQ(first_done, 4000);
  VT_EXPECT_EQ(done_ticks, 2000);
  // A new trial restarts the count.
  VT_EXPECT_EQ(Code(generator.StartSine(config)), Code(TrajectoryError::kOk));
  const TrajectoryPoint p = generator.Step();
  VT_EXPECT_EQ(p.repetition, 0);
  VT_EXPECT_TRUE(p.segment == Segment::kFlexionLoading);
  VT_EXPECT_TRUE(!p.done);
}

// Paper Fig. 7: the amplitude grows linearly over the cycles. Every sample against the
// double reference, and the envelope at every peak and trough.
MJC_VECTOR_TEST(SweepTrajectory, EnvelopeMatchesDoubleReference) {
  RampedSineConfig config;
  config.neutral = 0.1_rad;
  config.start_amplitude = 2.0_deg;
  config.end_amplitude = 30.0_deg;
  config.frequency = 1.0_Hz;
  config.repetitions = 4;
  config.rest_ms = 500;
  const Trial trial = TrialOf(config);
  VT_EXPECT_EQ(trial.cycle, 10000);

  TrajectoryGenerator generator;
  VT_EXPECT_EQ(Code(generator.StartSweep(config)), Code(TrajectoryError::kOk));
  const TrialResult r = RunTrial(generator, trial);
  ExpectReference(vt_context, r, trial, 1.05, 2.2);

  // Envelope: |position − neutral| at each peak and trough is A(k) itself (sin = ±1
  // exactly there, so the product is exact): only the ramp's rounding, <= 0.5 LSB.
  TrajectoryGenerator again;
  VT_EXPECT_EQ(Code(again.StartSweep(config)), Code(TrajectoryError::kOk));
  const double cycling = static_cast<double>(trial.cycle * trial.repetitions);
  double worst = 0;
  double previous_peak = 0;
  bool growing = true;
  for (std::int64_t t = 0; t < trial.rest + trial.cycle * trial.repetitions; ++t) {
    const TrajectoryPoint p = again.Step();
    const std::int64_t k = t - trial.rest;
    if (k < 0) continue;
    const std::int64_t i = k % trial.cycle;
    if (i != trial.cycle / 4 && i != 3 * trial.cycle / 4) continue;
    const double envelope =
        trial.start_amplitude +
        (trial.end_amplitude - trial.start_amplitude) * static_cast<double>(k) / cycling;
    const double excursion = std::fabs(p.position.ToDouble() - trial.neutral);
    const double e = std::fabs(excursion - envelope) / kAngleLsb;
    worst = e > worst ? e : worst;
    growing = growing && excursion > previous_peak;
    previous_peak = excursion;
  }
  VT_EXPECT_LE(worst, 0.5);
  VT_EXPECT_TRUE(growing);
  // The last trough, 3.75 of 4 cycles in: 2° + 28°·0.9375 = 28.25°.
  VT_EXPECT_NEAR(previous_peak, 28.25 * std::numbers::pi / 180.0, 2 * kAngleLsb);
}

MJC_VECTOR_TEST(SweepTrajectory, FromZeroAndDecreasing) {
  RampedSineConfig rising;
  rising.neutral = -0.2_rad;
  rising.start_amplitude = Angle{};
  rising.end_amplitude = 10.0_deg;
  rising.frequency = 2.5_Hz;
  rising.repetitions = 3;
  rising.rest_ms = 10;
  RampedSineConfig falling = rising;
  falling.start_amplitude = 20.0_deg;
  falling.end_amplitude = 5.0_deg;
  for (const RampedSineConfig& config : {rising, falling}) {
    TrajectoryGenerator generator;
    VT_EXPECT_EQ(Code(generator.StartSweep(config)), Code(TrajectoryError::kOk));
    VT_EXPECT_TRUE(generator.mode() == TrajectoryMode::kSweep);
    const Trial trial = TrialOf(config);
    const TrialResult r = RunTrial(generator, trial);
    ExpectReference(vt_context, r, trial, 1.05, 2.2);
  }
}

MJC_VECTOR_TEST(HoldTrajectory, ConstantPositionZeroVelocity) {
  TrajectoryGenerator generator;
  generator.Hold(-1.25_rad);
  VT_EXPECT_TRUE(generator.mode() == TrajectoryMode::kHold);
  int wrong = 0;
  for (int t = 0; t < 5000; ++t) {
    const TrajectoryPoint p = generator.Step();
    if (!(p.position == -1.25_rad) || p.velocity.raw() != 0 ||
        p.segment != Segment::kHold || p.repetition != 0 || p.done) {
      ++wrong;
    }
  }
  VT_EXPECT_EQ(wrong, 0);
}

// Random targets from a 1 kHz and a 100 Hz host: no step exceeds max_rate·dt, the
// reported velocity is the step taken, the setpoint never overshoots, and a target held
// still is reached in the fewest ticks the rate allows.
MJC_VECTOR_TEST(StreamTrajectory, RateLimitedAndReachesTarget) {
  struct Case {
    AngularVelocity max_rate;
    int ticks_per_update;  // 10 -> 1 kHz, 100 -> 100 Hz
    std::uint64_t seed;
  };
  const Case cases[] = {
      {0.5_rad_s, 10, 301}, {2.0_rad_s, 100, 302}, {0.01_rad_s, 10, 303}};
  for (const Case& k : cases) {
    TrajectoryGenerator generator;
    const Angle from = 0.25_rad;
    VT_EXPECT_EQ(Code(generator.StartStream(from, k.max_rate)),
                 Code(TrajectoryError::kOk));
    const double bound_lsb = k.max_rate.ToDouble() / 10000.0 / kAngleLsb;  // max_rate·dt
    Rng rng(k.seed);
    Angle previous = from;
    Angle target = from;
    double worst_step = 0;
    double worst_velocity = 0;
    int overshoots = 0;
    int wrong_labels = 0;
    for (int t = 0; t < 20000; ++t) {
      if (t % k.ticks_per_update == 0) {
        // Targets within ±1 rad of `from`.
        target = Angle::FromRaw(from.raw() + (rng.NextI32() >> 7));
        VT_EXPECT_EQ(Code(generator.SetStreamTarget(target)), Code(TrajectoryError::kOk));
      }
      const TrajectoryPoint p = generator.Step();
      const double step = static_cast<double>(p.position.raw()) - previous.raw();
      const double step_lsb = std::fabs(step);
      worst_step = step_lsb > worst_step ? step_lsb : worst_step;
      // Velocity = step · f_tick, rounded once.
      const double ev =
          std::fabs(p.velocity.ToDouble() - step * kAngleLsb * 10000.0) / kVelocityLsb;
      worst_velocity = ev > worst_velocity ? ev : worst_velocity;
      VT_EXPECT_TRUE(p.velocity <= k.max_rate && p.velocity >= -k.max_rate);
      const double before = static_cast<double>(target.raw()) - previous.raw();
      const double after = static_cast<double>(target.raw()) - p.position.raw();
      if ((before > 0 && after < 0) || (before < 0 && after > 0) ||
          std::fabs(after) > std::fabs(before)) {
        ++overshoots;
      }
      if (p.segment != Segment::kStream || p.done || p.repetition != 0) ++wrong_labels;
      previous = p.position;
    }
    VT_EXPECT_LE(worst_step, bound_lsb);
    VT_EXPECT_TRUE(worst_step > bound_lsb - 1.0);  // it does run at the limit
    VT_EXPECT_LE(worst_velocity, 0.5);
    VT_EXPECT_EQ(overshoots, 0);
    VT_EXPECT_EQ(wrong_labels, 0);

    // A held target 0.3 rad away: reached no sooner than the rate allows and no later
    // than with steps 1 LSB short of it; then it stays, at velocity 0.
    const Angle goal = previous + 0.3_rad;
    VT_EXPECT_EQ(Code(generator.SetStreamTarget(goal)), Code(TrajectoryError::kOk));
    const auto distance_lsb = static_cast<double>((0.3_rad).raw());
    const auto fastest = static_cast<std::int64_t>(std::ceil(distance_lsb / bound_lsb));
    const auto slowest =
        static_cast<std::int64_t>(std::ceil(distance_lsb / (bound_lsb - 1.0)));
    std::int64_t arrived = -1;
    for (std::int64_t t = 1; t <= slowest + 10; ++t) {
      const TrajectoryPoint p = generator.Step();
      if (arrived < 0 && p.position == goal) arrived = t;
      if (arrived > 0 && t > arrived) {
        VT_EXPECT_TRUE(p.position == goal);
        VT_EXPECT_EQ(p.velocity.raw(), 0);
      }
    }
    VT_EXPECT_TRUE(arrived >= fastest);
    VT_EXPECT_TRUE(arrived <= slowest);
  }
}

MJC_VECTOR_TEST(StreamTrajectory, RefusedRatesKeepOldTrajectory) {
  TrajectoryGenerator generator;
  VT_EXPECT_EQ(Code(generator.SetStreamTarget(1.0_rad)),
               Code(TrajectoryError::kNotStreaming));
  generator.Hold(0.7_rad);
  VT_EXPECT_EQ(Code(generator.StartStream(0.0_rad, AngularVelocity{})),
               Code(TrajectoryError::kRateNotPositive));
  VT_EXPECT_EQ(Code(generator.StartStream(0.0_rad, -1.0_rad_s)),
               Code(TrajectoryError::kRateNotPositive));
  // 1 LSB of Angle per tick at 10 kHz is 5.96e-4 rad/s; just below it is refused, at it
  // accepted.
  VT_EXPECT_EQ(Code(generator.StartStream(0.0_rad, 0.0005_rad_s)),
               Code(TrajectoryError::kRateBelowResolution));
  VT_EXPECT_EQ(Code(generator.SetStreamTarget(1.0_rad)),
               Code(TrajectoryError::kNotStreaming));
  VT_EXPECT_TRUE(generator.mode() == TrajectoryMode::kHold);
  const TrajectoryPoint p = generator.Step();
  VT_EXPECT_TRUE(p.position == 0.7_rad);
  VT_EXPECT_TRUE(p.segment == Segment::kHold);

  VT_EXPECT_EQ(Code(generator.StartStream(0.0_rad, 0.0006_rad_s)),
               Code(TrajectoryError::kOk));
  VT_EXPECT_EQ(Code(generator.SetStreamTarget(1.0_rad)), Code(TrajectoryError::kOk));
  VT_EXPECT_EQ(generator.Step().position.raw(), 1);
}

// Every refusal returns its own stable code, Validate() agrees, and the running trial
// continues bit for bit as if nothing had been sent (compared with a twin generator
// that never saw the bad configurations).
MJC_VECTOR_TEST(TrajectoryConfig, RefusedConfigsKeepOldTrajectory) {
  const SineConfig good = PaperTrial();
  TrajectoryGenerator generator;
  TrajectoryGenerator twin;
  VT_EXPECT_EQ(Code(generator.StartSine(good)), Code(TrajectoryError::kOk));
  VT_EXPECT_EQ(Code(twin.StartSine(good)), Code(TrajectoryError::kOk));
  for (int t = 0; t < 42345; ++t) {  // into the extension loading of cycle 0
    generator.Step();
    twin.Step();
  }

  struct Bad {
    SineConfig config;
    TrajectoryError error;
  };
  Bad bad[12] = {};
  for (Bad& b : bad) b.config = good;
  bad[0].config.amplitude = Angle{};
  bad[0].error = TrajectoryError::kAmplitudeNotPositive;
  bad[1].config.amplitude = -5.0_deg;
  bad[1].error = TrajectoryError::kAmplitudeNotPositive;
  bad[2].config.amplitude = mjc::kMaxTrajectoryAmplitude + Angle::Epsilon();
  bad[2].error = TrajectoryError::kAmplitudeTooLarge;
  bad[3].config.amplitude = 25.0_rad;  // degrees sent as radians
  bad[3].error = TrajectoryError::kAmplitudeTooLarge;
  bad[4].config.frequency = Frequency{};
  bad[4].error = TrajectoryError::kFrequencyNotPositive;
  bad[5].config.frequency = 2500.0_Hz + Frequency::Epsilon();
  bad[5].error = TrajectoryError::kFrequencyTooHigh;
  bad[6].config.repetitions = 0;
  bad[6].error = TrajectoryError::kZeroRepetitions;
  bad[7].config.rest_ms = mjc::kMaxRestMs + 1;
  bad[7].error = TrajectoryError::kRestTooLong;
  bad[8].config.tick_rate_hz = 0;
  bad[8].error = TrajectoryError::kTickRateOutOfRange;
  bad[9].config.tick_rate_hz = 20000;
  bad[9].error = TrajectoryError::kTickRateMismatch;
  bad[10].config.neutral = Angle::Max() - 0.2_rad;
  bad[10].error = TrajectoryError::kSetpointOutOfRange;
  bad[11].config.amplitude = 3.0_rad;  // 3 rad · 2π · 200 Hz = 3770 rad/s > 2048
  bad[11].config.frequency = 200.0_Hz;
  bad[11].error = TrajectoryError::kVelocityOutOfRange;

  int diverged = 0;
  for (const Bad& b : bad) {
    VT_EXPECT_EQ(Code(generator.StartSine(b.config)), Code(b.error));
    if (b.error != TrajectoryError::kTickRateMismatch) {
      VT_EXPECT_EQ(Code(mjc::Validate(b.config)), Code(b.error));
    } else {
      VT_EXPECT_EQ(Code(mjc::Validate(b.config)), Code(TrajectoryError::kOk));
    }
    for (int t = 0; t < 50; ++t) {
      const TrajectoryPoint a = generator.Step();
      const TrajectoryPoint e = twin.Step();
      if (!(a.position == e.position) || !(a.velocity == e.velocity) ||
          a.segment != e.segment || a.repetition != e.repetition || a.done != e.done) {
        ++diverged;
      }
    }
  }
  VT_EXPECT_EQ(diverged, 0);
  VT_EXPECT_EQ(Code(generator.StartStream(0.0_rad, AngularVelocity{})),
               Code(TrajectoryError::kRateNotPositive));
  VT_EXPECT_TRUE(generator.mode() == TrajectoryMode::kSine);

  // Sweep-only checks, against the same running trial.
  RampedSineConfig sweep;
  sweep.neutral = 0.0_rad;
  sweep.start_amplitude = -1.0_deg;
  sweep.end_amplitude = 20.0_deg;
  sweep.frequency = 0.5_Hz;
  VT_EXPECT_EQ(Code(generator.StartSweep(sweep)),
               Code(TrajectoryError::kAmplitudeNegative));
  sweep.start_amplitude = 2.0_deg;
  sweep.end_amplitude = Angle{};
  VT_EXPECT_EQ(Code(generator.StartSweep(sweep)),
               Code(TrajectoryError::kAmplitudeNotPositive));
  sweep.end_amplitude = 4.0_rad;
  VT_EXPECT_EQ(Code(generator.StartSweep(sweep)),
               Code(TrajectoryError::kAmplitudeTooLarge));
  const TrajectoryPoint a = generator.Step();
  const TrajectoryPoint e = twin.Step();
  VT_EXPECT_TRUE(a.position == e.position && a.segment == e.segment);
}

// The edges of the legal ranges are accepted.
MJC_VECTOR_TEST(TrajectoryConfig, EdgesAreAccepted) {
  SineConfig c;
  c.amplitude = mjc::kMaxTrajectoryAmplitude;
  c.frequency = 0.5_Hz;
  c.repetitions = 1;
  c.rest_ms = mjc::kMaxRestMs;
  VT_EXPECT_EQ(Code(mjc::Validate(c)), Code(TrajectoryError::kOk));
  c.amplitude = 0.1_rad;  // 0.1 · 2π · 2500 = 1571 rad/s
  c.frequency = 2500.0_Hz;
  VT_EXPECT_EQ(Code(mjc::Validate(c)), Code(TrajectoryError::kOk));
  c.frequency = Frequency::Epsilon();  // 2^-16 Hz: 655,360,000 ticks a cycle
  c.repetitions = 65535;
  VT_EXPECT_EQ(Code(mjc::Validate(c)), Code(TrajectoryError::kOk));
  c.tick_rate_hz = mjc::kMaxTickRateHz;
  VT_EXPECT_EQ(Code(mjc::Validate(c)), Code(TrajectoryError::kOk));
  c.tick_rate_hz = mjc::kMaxTickRateHz + 1;
  VT_EXPECT_EQ(Code(mjc::Validate(c)), Code(TrajectoryError::kTickRateOutOfRange));

  // A 20 kHz board runs 0.5 Hz in 40,000 ticks.
  TrajectoryGenerator generator(20000);
  SineConfig fast = PaperTrial();
  fast.tick_rate_hz = 20000;
  fast.repetitions = 1;
  fast.rest_ms = 1;
  VT_EXPECT_EQ(Code(generator.StartSine(fast)), Code(TrajectoryError::kOk));
  VT_EXPECT_EQ(generator.ticks_per_cycle(), 40000u);
  VT_EXPECT_EQ(generator.rest_ticks(), 20u);
  const TrialResult r = RunTrial(generator, TrialOf(fast));
  VT_EXPECT_EQ(r.label_mismatches, 0);
  VT_EXPECT_LE(r.position_lsb, 0.55);
  VT_EXPECT_LE(r.velocity_lsb, 1.05);

  // A generator built with an illegal tick rate refuses every start but still holds.
  TrajectoryGenerator broken(0);
  SineConfig zero = PaperTrial();
  zero.tick_rate_hz = 0;
  VT_EXPECT_EQ(Code(broken.StartSine(zero)), Code(TrajectoryError::kTickRateOutOfRange));
  VT_EXPECT_EQ(Code(broken.StartStream(0.0_rad, 1.0_rad_s)),
               Code(TrajectoryError::kTickRateOutOfRange));
  broken.Hold(0.1_rad);
  VT_EXPECT_TRUE(broken.Step().position == 0.1_rad);
}

MJC_VECTOR_TEST(TrajectoryStop, IdlesAtLastSetpoint) {
  TrajectoryGenerator generator(mjc::kDefaultTickRateHz, 0.4_rad);
  TrajectoryPoint p = generator.Step();
  VT_EXPECT_TRUE(p.position == 0.4_rad && p.segment == Segment::kIdle && p.done);
  VT_EXPECT_EQ(Code(generator.StartSine(PaperTrial())), Code(TrajectoryError::kOk));
  TrajectoryPoint last;
  for (int t = 0; t < 30000 + 3210; ++t) last = generator.Step();
  VT_EXPECT_TRUE(last.segment == Segment::kFlexionLoading);
  VT_EXPECT_TRUE(last.position > PaperTrial().neutral);
  generator.Stop();
  for (int t = 0; t < 100; ++t) {
    p = generator.Step();
    VT_EXPECT_TRUE(p.position == last.position);
    VT_EXPECT_EQ(p.velocity.raw(), 0);
    VT_EXPECT_TRUE(p.segment == Segment::kIdle);
    VT_EXPECT_TRUE(p.done);
    VT_EXPECT_EQ(p.repetition, 0);
  }
  VT_EXPECT_TRUE(generator.mode() == TrajectoryMode::kIdle);
  VT_EXPECT_EQ(generator.ticks_per_cycle(), 0u);

  // Stop during a stream idles where the stream had got to.
  VT_EXPECT_EQ(Code(generator.StartStream(last.position, 1.0_rad_s)),
               Code(TrajectoryError::kOk));
  VT_EXPECT_EQ(Code(generator.SetStreamTarget(last.position + 1.0_rad)),
               Code(TrajectoryError::kOk));
  for (int t = 0; t < 10; ++t) p = generator.Step();
  generator.Stop();
  VT_EXPECT_TRUE(generator.Step().position == p.position);
}

}  // namespace
