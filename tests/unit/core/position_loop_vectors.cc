// Position loop against a double-precision reference of its documented algorithm, and
// against hand-derived values. These vectors run on the host and on the Cortex-M4 under
// QEMU.
//
// The documented algorithm (position_loop.h), per tick at f = tick_hz:
//   ω_raw = (θ_m − θ_m,prev)·f,  ω_f += β·(ω_raw − ω_f)   (ω_f = 0 and θ_m,prev = θ_m on
//                                                          the first tick)
//   e = θ_set − θ_m,  P = kp·e,  D = −kd·ω_f,  FF = kff·θ̇_set
//   before = P + D + FF + I; no integration if (before ≥ max_duty and e > 0) or
//   (before ≤ −max_duty and e < 0), else I = clamp(I + ki·e/f, ±integral_limit)
//   duty = clamp(P + D + FF + I, ±max_duty)
// The reference uses the config's own (quantised) gains as doubles, so what it measures
// is the arithmetic of the loop, not the quantisation of the gains.
//
// Error bounds, derived from the rounding steps (LSB of Q24 is 2^-24, of Duty 2^-15):
//   P, FF: one rounding of an exact product to Q24: <= 2^-25.
//   ω_f: the backward difference is exact in Q24 and rounds once to Q20 (<= 0.5 LSB);
//        the filter update rounds once a tick (<= 0.5 LSB), and the (1 − β) recursion
//        sums both to at most 0.5 + 0.5/β LSB of Q20.
//   D:   kd·(0.5 + 0.5/β)·2^-20 + 2^-25.
//   I:   each step rounds once to Q24 (2^-25) and uses ki/f held in Q30 (<= 2^-31 per
//        rad of error): <= 2^-25 + 2^-31·|e| a step. Clamp is 1-Lipschitz, so a step's
//        error never grows through it, and a clamp both loops reach decisively resets
//        the difference to zero.
//   duty: one rounding to Q15 (0.5 LSB) plus the sum of the above; a duty the reference
//        puts beyond ±max_duty by more than that sum equals ±max_duty exactly.
// Ticks whose integration decision lies within the accumulated bound of the limit are
// ambiguous: either decision is correct there, and the reference follows the branch
// closer to the loop (they are counted, and stay rare).
#include <cstdint>
#include <numbers>

#include "mjc/core/position_loop.h"
#include "mjc/core/quantities.h"
#include "vector_test.h"

namespace {

using mjc::Angle;
using mjc::AngularVelocity;
using mjc::Duty;
using mjc::PositionLoop;
using mjc::PositionLoopConfig;
using mjc::PositionLoopError;
using mjc::vt::Rng;

using Kp = decltype(PositionLoopConfig::kp);
using Ki = decltype(PositionLoopConfig::ki);
using Kd = decltype(PositionLoopConfig::kd);
using Kff = decltype(PositionLoopConfig::kff);
using Beta = decltype(PositionLoopConfig::velocity_filter);

constexpr double kQ15 = 1.0 / 32768.0;       // Duty LSB
constexpr double kQ20 = 1.0 / 1048576.0;     // AngularVelocity LSB
constexpr double kQ24 = 1.0 / 16777216.0;    // Angle and DutySum LSB
constexpr double kQ31 = 1.0 / 2147483648.0;  // half an LSB of the Q30 ki / f
constexpr double kReferenceSlack = 1e-12;    // double rounding of the reference
constexpr int kSigns[] = {1, -1};
constexpr double kPulleyCount = 2.0 * std::numbers::pi / 204800.0;  // 2048 edges, 100:1

double AbsD(double x) { return x < 0 ? -x : x; }
double MaxD(double a, double b) { return a > b ? a : b; }
double ClampD(double x, double lo, double hi) { return x < lo ? lo : (x > hi ? hi : x); }

std::int64_t RoundToInt(double x) {
  return static_cast<std::int64_t>(x < 0 ? x - 0.5 : x + 0.5);
}

// Uniform in [lo, hi).
double Uniform(Rng& rng, double lo, double hi) {
  return lo +
         (hi - lo) * static_cast<double>(rng.Next() >> 11) * (1.0 / 9007199254740992.0);
}

struct Gains {
  double kp, ki, kd, kff, max_duty, integral_limit, beta;
  std::uint32_t tick_hz;
};

PositionLoopConfig MakeConfig(const Gains& g) {
  PositionLoopConfig c;
  c.kp = Kp::Quantize(g.kp);
  c.ki = Ki::Quantize(g.ki);
  c.kd = Kd::Quantize(g.kd);
  c.kff = Kff::Quantize(g.kff);
  c.max_duty = Duty::Quantize(g.max_duty);
  c.integral_limit = Duty::Quantize(g.integral_limit);
  c.velocity_filter = Beta::Quantize(g.beta);
  c.tick_hz = g.tick_hz;
  return c;
}

// The documented algorithm in double precision. One tick is Begin() (terms and the
// integration decision) then Finish() (integrator and output).
class ReferenceLoop {
 public:
  explicit ReferenceLoop(const PositionLoopConfig& c)
      : kp_(c.kp.ToDouble()),
        ki_per_tick_(c.ki.ToDouble() / static_cast<double>(c.tick_hz)),
        kd_(c.kd.ToDouble()),
        kff_(c.kff.ToDouble()),
        limit_(c.max_duty.ToDouble()),
        integral_limit_(c.integral_limit.ToDouble()),
        beta_(c.velocity_filter.ToDouble()),
        tick_hz_(static_cast<double>(c.tick_hz)) {}

  void Begin(double setpoint, double setpoint_velocity, double motor) {
    if (!initialized_) {
      last_motor_ = motor;
      velocity_ = 0;
      integral_ = 0;
      initialized_ = true;
    }
    const double raw_velocity = (motor - last_motor_) * tick_hz_;
    last_motor_ = motor;
    velocity_ += beta_ * (raw_velocity - velocity_);
    error_ = setpoint - motor;
    p_ = kp_ * error_;
    d_ = -kd_ * velocity_;
    ff_ = kff_ * setpoint_velocity;
    before_ = p_ + d_ + ff_ + integral_;
  }

  bool Integrates() const {
    const bool pushing_high = before_ >= limit_ && error_ > 0;
    const bool pushing_low = before_ <= -limit_ && error_ < 0;
    return !pushing_high && !pushing_low;
  }

  // Distance of `before` from the edge that decides this tick (error = 0 integrates
  // nothing, so it is never ambiguous).
  double DecisionMargin() const {
    if (error_ > 0) return AbsD(before_ - limit_);
    if (error_ < 0) return AbsD(before_ + limit_);
    return 1e300;
  }

  // The integral if this tick integrates (unclamped, then clamped).
  double UnclampedStep() const { return integral_ + ki_per_tick_ * error_; }
  double IntegratedValue() const {
    return ClampD(UnclampedStep(), -integral_limit_, integral_limit_);
  }

  void Finish(bool integrate) {
    if (integrate) integral_ = IntegratedValue();
    total_ = p_ + d_ + ff_ + integral_;
  }

  double error() const { return error_; }
  double p() const { return p_; }
  double d() const { return d_; }
  double ff() const { return ff_; }
  double integral() const { return integral_; }
  double total() const { return total_; }
  double duty() const { return ClampD(total_, -limit_, limit_); }
  double limit() const { return limit_; }
  double integral_limit() const { return integral_limit_; }
  double ki_per_tick() const { return ki_per_tick_; }

 private:
  double kp_, ki_per_tick_, kd_, kff_, limit_, integral_limit_, beta_, tick_hz_;
  bool initialized_ = false;
  double last_motor_ = 0, velocity_ = 0, integral_ = 0;
  double error_ = 0, p_ = 0, d_ = 0, ff_ = 0, before_ = 0, total_ = 0;
};

// Mean ticks between random events of the plant and the setpoint source: 0.15 s, but at
// most 2000 ticks, so short runs at fast tick rates see many events too.
std::uint64_t EventPeriod(double tick_hz) {
  const double ticks = 0.15 * tick_hz;
  return static_cast<std::uint64_t>(ticks < 2000.0 ? (ticks < 1.0 ? 1.0 : ticks)
                                                   : 2000.0);
}

// A motor pulley driven by the loop's duty: first-order speed response (10 rad/s per
// unit duty, 10 ms), a random load that changes now and then, read through a
// 2048-edge, 100:1 quadrature encoder.
class Plant {
 public:
  explicit Plant(double tick_hz) : dt_(1.0 / tick_hz), period_(EventPeriod(tick_hz)) {}
  void Step(double duty, Rng& rng) {
    if (rng.Next() % period_ == 0) load_ = Uniform(rng, -2.0, 2.0);
    velocity_ += dt_ / 0.01 * (10.0 * duty + load_ - velocity_);
    angle_ += velocity_ * dt_;
  }
  Angle Measured() const {
    return Angle::Quantize(static_cast<double>(RoundToInt(angle_ / kPulleyCount)) *
                           kPulleyCount);
  }

 private:
  double dt_;
  std::uint64_t period_;
  double angle_ = 0, velocity_ = 0, load_ = 0;
};

// Setpoints as a host streams them: holds, ramps (with their velocity as feed-forward),
// small and large steps, within ±1.6 rad.
class SetpointSource {
 public:
  SetpointSource(double tick_hz, Rng& rng)
      : dt_(1.0 / tick_hz),
        period_(EventPeriod(tick_hz)),
        angle_(Uniform(rng, -1.0, 1.0)) {}
  void Step(Rng& rng) {
    if (rng.Next() % period_ == 0) {
      switch (rng.Next() % 4u) {
        case 0:
          velocity_ = 0;
          break;
        case 1:
          velocity_ = Uniform(rng, -2.0, 2.0);
          break;
        case 2:
          velocity_ = 0;
          angle_ += Uniform(rng, -0.2, 0.2);
          break;
        default:
          velocity_ = 0;
          angle_ = Uniform(rng, -1.5, 1.5);
          break;
      }
    }
    angle_ += velocity_ * dt_;
    if (angle_ > 1.6 || angle_ < -1.6) {
      angle_ = ClampD(angle_, -1.6, 1.6);
      velocity_ = -velocity_;
    }
  }
  Angle angle() const { return Angle::Quantize(angle_); }
  AngularVelocity velocity() const { return AngularVelocity::Quantize(velocity_); }

 private:
  double dt_;
  std::uint64_t period_;
  double angle_, velocity_ = 0;
};

struct DiffStats {
  double worst_duty_lsb = 0;  // |duty − reference| in Duty LSB
  double worst_integral = 0;  // |I − reference I|
  int ambiguous = 0;          // ticks whose integration decision was within the bound
  int saturated = 0;          // ticks the reference puts beyond ±max_duty
  int held = 0;               // ticks the reference does not integrate
  int integral_clamped = 0;   // ticks the reference integral sits at ±integral_limit
};

// Runs the loop in closed loop with the plant for `ticks` ticks and checks every term,
// the integrator step and the duty against the reference and the bounds above.
DiffStats RunDifferential(mjc::vt::Context& vt_context, const Gains& gains,
                          std::uint64_t seed, int ticks) {
  // Setup
  const PositionLoopConfig config = MakeConfig(gains);
  VT_EXPECT_TRUE(mjc::Validate(config) == PositionLoopError::kOk);
  PositionLoop::State state;
  PositionLoop loop(&config, &state);
  ReferenceLoop ref(config);
  Rng rng(seed);
  Plant plant(static_cast<double>(gains.tick_hz));
  SetpointSource source(static_cast<double>(gains.tick_hz), rng);

  const double bound_p = kQ24 / 2 + kReferenceSlack;
  const double bound_ff = kQ24 / 2 + kReferenceSlack;
  const double bound_d =
      config.kd.ToDouble() * (0.5 + 0.5 / config.velocity_filter.ToDouble()) * kQ20 +
      kQ24 / 2 + kReferenceSlack;
  const double fw_limit = config.max_duty.ToDouble();
  const double fw_integral_limit = config.integral_limit.ToDouble();
  double integral_slack = 0;  // proven bound on |I − reference I|

  DiffStats stats;
  int term_failures = 0, step_failures = 0, integral_failures = 0, duty_failures = 0,
      saturation_failures = 0;
  for (int t = 0; t < ticks; ++t) {
    // Exercise
    source.Step(rng);
    const Angle setpoint = source.angle();
    const AngularVelocity setpoint_velocity = source.velocity();
    const Angle motor = plant.Measured();
    const double integral_before = state.integral.ToDouble();
    ref.Begin(setpoint.ToDouble(), setpoint_velocity.ToDouble(), motor.ToDouble());
    const Duty duty = loop.Update(setpoint, setpoint_velocity, motor);
    const PositionLoop::Status& s = loop.status();
    const double integral_after = state.integral.ToDouble();

    // Verify: the terms.
    if (AbsD(s.p.ToDouble() - ref.p()) > bound_p) ++term_failures;
    if (AbsD(s.ff.ToDouble() - ref.ff()) > bound_ff) ++term_failures;
    if (AbsD(s.d.ToDouble() - ref.d()) > bound_d) ++term_failures;
    if (s.i != state.integral) ++term_failures;

    // Verify: the integrator step, from the loop's own previous integral.
    const double step_bound = kQ24 / 2 + kQ31 * AbsD(ref.error()) + kReferenceSlack;
    const double tol = bound_p + bound_d + bound_ff + integral_slack;
    const bool ambiguous = ref.DecisionMargin() <= tol;
    const bool integrates = ref.Integrates();
    const double stepped = ClampD(integral_before + ref.ki_per_tick() * ref.error(),
                                  -fw_integral_limit, fw_integral_limit);
    const bool step_ok = AbsD(integral_after - stepped) <= step_bound;
    const bool hold_ok = integral_after == integral_before;
    if (ambiguous ? !(step_ok || hold_ok) : (integrates ? !step_ok : !hold_ok)) {
      ++step_failures;
    }

    // The reference's integrator, and the bound on its distance from the loop's.
    bool take_step = integrates;
    if (ambiguous) {
      ++stats.ambiguous;
      const double if_held = ref.integral();
      const double if_stepped = ref.IntegratedValue();
      take_step = AbsD(integral_after - if_stepped) < AbsD(integral_after - if_held);
    }
    if (take_step) {
      const double unclamped = ref.UnclampedStep();
      integral_slack += step_bound;
      if (AbsD(unclamped) - ref.integral_limit() > integral_slack) integral_slack = 0;
    } else if (ambiguous) {
      integral_slack += step_bound;
    }
    if (!integrates) ++stats.held;
    ref.Finish(take_step);
    if (AbsD(ref.integral()) == ref.integral_limit()) ++stats.integral_clamped;
    const double integral_error = AbsD(integral_after - ref.integral());
    stats.worst_integral = MaxD(stats.worst_integral, integral_error);
    if (integral_error > integral_slack + kReferenceSlack) ++integral_failures;

    // Verify: the duty.
    const double total_bound = bound_p + bound_d + bound_ff + integral_slack;
    const double duty_error = AbsD(duty.ToDouble() - ref.duty());
    stats.worst_duty_lsb = MaxD(stats.worst_duty_lsb, duty_error / kQ15);
    if (duty_error > kQ15 / 2 + total_bound) ++duty_failures;
    const double beyond = AbsD(ref.total()) - ref.limit();
    if (beyond > total_bound) {
      ++stats.saturated;
      const Duty edge = ref.total() > 0 ? config.max_duty : -config.max_duty;
      if (duty != edge || !s.saturated) ++saturation_failures;
    } else if (beyond < -total_bound) {
      if (s.saturated || AbsD(duty.ToDouble()) > fw_limit) ++saturation_failures;
    }

    plant.Step(duty.ToDouble(), rng);
  }
  VT_EXPECT_EQ(term_failures, 0);
  VT_EXPECT_EQ(step_failures, 0);
  VT_EXPECT_EQ(integral_failures, 0);
  VT_EXPECT_EQ(duty_failures, 0);
  VT_EXPECT_EQ(saturation_failures, 0);
  return stats;
}

// The duty agrees with the reference to this many Duty LSB over every differential run
// below (observed worst 0.58, 0.80, 0.52, 0.65 LSB in the four fixed configs, 0.72 over
// the random ones). The rounding to Q15 alone contributes 0.5; the P and FF roundings
// 2^-10 each; the velocity filter's dead band kd·(0.5 + 0.5/β)·2^-20, at most 0.16 LSB
// here (kd 0.1, β 0.01) and 0.03 LSB elsewhere; the rest is the integrator's rounding,
// <= 2^-25 a step (0.35 LSB observed after 2.5e4 ticks). Unlike the other terms that
// one accumulates while the integral is off its clamps, so its proven bound (checked
// every tick above) grows with the run; this constant is the tight check.
constexpr double kDutyBoundLsb = 1.0;

void CheckCoverage(mjc::vt::Context& vt_context, const DiffStats& s, int ticks,
                   bool uses_integral) {
  VT_EXPECT_LE(s.worst_duty_lsb, kDutyBoundLsb);
  // Ambiguous decisions stay rare, so the reference mostly decides for itself.
  VT_EXPECT_LE(s.ambiguous, ticks / 1000);
  // The run reaches saturation and anti-windup holds, not just the linear region.
  VT_EXPECT_TRUE(s.saturated > ticks / 100);
  if (uses_integral) VT_EXPECT_TRUE(s.held > ticks / 100);
}

constexpr int kDiffTicks = 25000;

MJC_VECTOR_TEST(PositionLoopDifferential, TenKilohertzFilteredVelocity) {
  const Gains g{8.0, 40.0, 0.2, 0.3, 0.9, 0.3, 0.05, 10000};
  const DiffStats s = RunDifferential(vt_context, g, 101, kDiffTicks);
  CheckCoverage(vt_context, s, kDiffTicks, true);
  VT_EXPECT_TRUE(s.integral_clamped > 0);
}

MJC_VECTOR_TEST(PositionLoopDifferential, StiffGainsUnfilteredIntegralUpToMaxDuty) {
  const Gains g{20.0, 200.0, 0.05, 0.33, 0.95, 0.95, 1.0, 20000};
  const DiffStats s = RunDifferential(vt_context, g, 102, kDiffTicks);
  CheckCoverage(vt_context, s, kDiffTicks, true);
}

MJC_VECTOR_TEST(PositionLoopDifferential, SlowTickNoIntegralHeavyDamping) {
  const Gains g{3.0, 5.0, 0.5, 0.0, 0.5, 0.0, 0.3, 1000};
  const DiffStats s = RunDifferential(vt_context, g, 103, kDiffTicks);
  CheckCoverage(vt_context, s, kDiffTicks, false);
  VT_EXPECT_EQ(s.worst_integral, 0.0);  // integral_limit 0 keeps I at zero
}

MJC_VECTOR_TEST(PositionLoopDifferential, FastTickHeavyFilterNegativeFeedForward) {
  const Gains g{12.0, 100.0, 0.1, -0.1, 0.6, 0.4, 0.01, 40000};
  const DiffStats s = RunDifferential(vt_context, g, 104, kDiffTicks);
  CheckCoverage(vt_context, s, kDiffTicks, true);
}

MJC_VECTOR_TEST(PositionLoopDifferential, RandomConfigs) {
  Rng rng(105);
  constexpr std::uint32_t kRates[] = {100, 1000, 10000, 25000, 100000};
  constexpr int kConfigs = 8;
  constexpr int kTicks = 4000;
  double worst = 0;
  for (int i = 0; i < kConfigs; ++i) {
    Gains g{};
    g.kp = Uniform(rng, 0.0, 30.0);
    g.tick_hz = kRates[rng.Next() % 5u];
    // ki / tick_hz <= 0.01: realistic gains, far inside the Q1.30 register that holds
    // ki per tick (IntegralGainAcrossDocumentedRange covers the rest of the range).
    g.ki = Uniform(rng, 0.0, 0.01 * static_cast<double>(g.tick_hz));
    g.kd = Uniform(rng, 0.0, 0.5);
    g.kff = Uniform(rng, -0.5, 0.5);
    g.max_duty = Uniform(rng, 0.2, 0.99);
    g.integral_limit = Uniform(rng, 0.0, g.max_duty);
    g.beta = Uniform(rng, 0.01, 1.0);
    const DiffStats s =
        RunDifferential(vt_context, g, 1050 + static_cast<std::uint64_t>(i), kTicks);
    worst = MaxD(worst, s.worst_duty_lsb);
    VT_EXPECT_LE(s.ambiguous, kTicks / 100);
  }
  VT_EXPECT_LE(worst, kDutyBoundLsb);
}

// ki is documented as [0, 2·tick_hz) duty per rad·s: every corner inside integrates
// ki·e/f a tick, and a gain at or above 2·tick_hz (which the Q1.30 per-tick register
// cannot hold) is refused rather than silently saturated.
MJC_VECTOR_TEST(PositionLoop, IntegralGainAcrossDocumentedRange) {
  struct Corner {
    double ki;
    std::uint32_t tick_hz;
    double error;
  };
  constexpr Corner kCorners[] = {
      {32767.0, 100000, 1e-3},  // ki/f = 0.32767
      {1.0, 100000, 0.5},       // ki/f = 1e-5
      {199.0, 100, 1e-3},       // ki/f = 1.99, just inside the register
      {19999.0, 10000, 1e-3},   // ki/f = 1.9999
  };
  for (const Corner& c : kCorners) {
    // Setup
    const PositionLoopConfig config =
        MakeConfig({0.0, c.ki, 0.0, 0.0, 0.99, 0.99, 1.0, c.tick_hz});
    VT_EXPECT_TRUE(mjc::Validate(config) == PositionLoopError::kOk);
    PositionLoop::State state;
    PositionLoop loop(&config, &state);
    // Exercise
    const Angle setpoint = Angle::Quantize(c.error);
    loop.Update(setpoint, AngularVelocity{}, Angle{});
    // Verify
    const double want = config.ki.ToDouble() / c.tick_hz * setpoint.ToDouble();
    VT_EXPECT_NEAR(state.integral.ToDouble(), want,
                   kQ24 / 2 + kQ31 * setpoint.ToDouble());
  }
  // At and beyond 2·tick_hz: refused with its own code.
  constexpr Corner kRefused[] = {{32767.0, 10000, 0}, {32767.0, 100, 0}, {200.0, 100, 0}};
  for (const Corner& c : kRefused) {
    const PositionLoopConfig config =
        MakeConfig({0.0, c.ki, 0.0, 0.0, 0.99, 0.99, 1.0, c.tick_hz});
    VT_EXPECT_TRUE(mjc::Validate(config) == PositionLoopError::kIntegralGainTooHigh);
  }
}

MJC_VECTOR_TEST(PositionLoop, FeedForwardOnly) {
  // Setup: only kff = 0.25 duty per rad/s.
  const PositionLoopConfig config =
      MakeConfig({0.0, 0.0, 0.0, 0.25, 0.9, 0.3, 0.05, 10000});
  PositionLoop::State state;
  PositionLoop loop(&config, &state);
  const std::int16_t max_raw = config.max_duty.raw();
  VT_EXPECT_EQ(max_raw, 29491);  // round(0.9 · 32768)

  // Hand values: 2 rad/s → 0.5, −1 rad/s → −0.25, ±3.6 and beyond clamp to ±0.9.
  struct Case {
    double velocity;
    std::int16_t duty_raw;
  };
  constexpr Case kCases[] = {{2.0, 16384},   {-1.0, -8192}, {0.0, 0},        {3.6, 29491},
                             {-3.6, -29491}, {10.0, 29491}, {-10.0, -29491}, {0.5, 4096}};
  Rng rng(201);
  for (const Case& c : kCases) {
    // Exercise: position error and motor motion must not matter.
    const Angle setpoint = Angle::Quantize(Uniform(rng, -1.5, 1.5));
    const Angle motor = Angle::Quantize(Uniform(rng, -1.5, 1.5));
    const Duty duty = loop.Update(setpoint, AngularVelocity::Quantize(c.velocity), motor);
    // Verify
    VT_EXPECT_EQ(duty.raw(), c.duty_raw);
    VT_EXPECT_EQ(loop.status().p.raw(), 0);
    VT_EXPECT_EQ(loop.status().d.raw(), 0);
    VT_EXPECT_EQ(loop.status().i.raw(), 0);
  }

  // Random velocities against kff·v, clamped.
  double worst = 0;
  int saturated = 0;
  for (int i = 0; i < 5000; ++i) {
    const AngularVelocity v = AngularVelocity::Quantize(Uniform(rng, -5.0, 5.0));
    const Duty duty = loop.Update(Angle::Quantize(Uniform(rng, -1.5, 1.5)), v,
                                  Angle::Quantize(Uniform(rng, -1.5, 1.5)));
    const double want = ClampD(0.25 * v.ToDouble(), -config.max_duty.ToDouble(),
                               config.max_duty.ToDouble());
    worst = MaxD(worst, AbsD(duty.ToDouble() - want) / kQ15);
    if (AbsD(want) == config.max_duty.ToDouble()) {
      ++saturated;
      VT_EXPECT_TRUE(loop.status().saturated);
    }
    VT_EXPECT_EQ(loop.status().i.raw(), 0);
  }
  VT_EXPECT_LE(worst, 0.5 + kQ24 / 2 / kQ15);
  VT_EXPECT_TRUE(saturated > 500);
}

MJC_VECTOR_TEST(PositionLoop, NoDerivativeKickOnSetpointSteps) {
  // Setup: P and D only, β = 0.5 so the filtered velocity is exact for a few ticks.
  const PositionLoopConfig config =
      MakeConfig({2.0, 0.0, 0.5, 0.0, 0.9, 0.3, 0.5, 10000});
  PositionLoop::State still_state;
  PositionLoop still(&config, &still_state);

  // A motor at rest: however the setpoint jumps, D is exactly zero.
  Rng rng(301);
  int nonzero_d = 0;
  for (int t = 0; t < 2000; ++t) {
    const Angle setpoint = Angle::Quantize(Uniform(rng, -1.5, 1.5));
    still.Update(setpoint, AngularVelocity{}, Angle::FromDouble(0.3));
    if (still.status().d.raw() != 0) ++nonzero_d;
  }
  VT_EXPECT_EQ(nonzero_d, 0);

  // A moving motor (2^-14 rad a tick, 0.6103515625 rad/s): D follows the motor only.
  // Loop A holds the setpoint at 0, loop B steps it to 0.125 rad at tick 2 and to
  // -0.25 rad at tick 4. By hand, ω_f = 0.6103515625·(1 − 2^-k) after k moving ticks
  // (the first tick has no previous sample, so ω_f = 0), D = −0.5·ω_f.
  PositionLoop::State a_state, b_state;
  PositionLoop a(&config, &a_state);
  PositionLoop b(&config, &b_state);
  constexpr double kStep = 1.0 / 16384.0;
  constexpr double kOmega = kStep * 10000.0;
  double filtered = 0;
  for (int t = 0; t < 6; ++t) {
    // Exercise
    const Angle motor = Angle::FromRaw(static_cast<std::int32_t>(1024 * t));
    const double b_setpoint = t < 2 ? 0.0 : (t < 4 ? 0.125 : -0.25);
    const Duty da = a.Update(Angle{}, AngularVelocity{}, motor);
    const Duty db = b.Update(Angle::Quantize(b_setpoint), AngularVelocity{}, motor);
    // Verify
    if (t > 0) filtered += 0.5 * (kOmega - filtered);
    VT_EXPECT_EQ(a.status().d.raw(), b.status().d.raw());
    VT_EXPECT_EQ(a.status().d.raw(), RoundToInt(-0.5 * filtered / kQ24));
    VT_EXPECT_EQ(a_state.motor_velocity.raw(), RoundToInt(filtered / kQ20));
    // The setpoint moves the duty through P alone: kp·Δsetpoint, exact here.
    VT_EXPECT_EQ(db.raw() - da.raw(), RoundToInt(2.0 * b_setpoint / kQ15));
  }
  VT_EXPECT_TRUE(a.status().d.raw() < -(1 << 20));  // D is live: below −0.0625
}

// Saturated integration on either side (sign = ±1): kp = 0.5, ki = 8 per rad·s at
// 10 kHz, max_duty 0.875, integral_limit 0.6, error 1 rad held for 5 s.
MJC_VECTOR_TEST(PositionLoop, AntiWindupHoldsIntegralAndLeavesSaturationAtOnce) {
  for (const int sign : kSigns) {
    // Setup
    const double sg = static_cast<double>(sign);
    const PositionLoopConfig config =
        MakeConfig({0.5, 8.0, 0.0, 0.0, 0.875, 0.6, 1.0, 10000});
    PositionLoop::State state;
    PositionLoop loop(&config, &state);
    const Angle motor = Angle::FromDouble(0.2);
    const Angle setpoint = Angle::Quantize(0.2 + sg);

    // Exercise: P = 0.5; I grows 8e-4 a tick. After k steps the output is
    // 0.5 + 8e-4·k, which first exceeds 0.875 at k = 469 (0.8752, vs 0.8744 at 468,
    // margins far above the 469·2^-25 = 1.4e-5 of rounding). From then on the error
    // pushes into saturation, so I holds at 0.3752 — never near integral_limit 0.6.
    int first_saturated = -1;
    std::int32_t held = 0;
    int moved_after_hold = 0;
    int wrong_duty = 0;
    for (int t = 1; t <= 50000; ++t) {
      const Duty duty = loop.Update(setpoint, AngularVelocity{}, motor);
      if (loop.status().saturated && first_saturated < 0) {
        first_saturated = t;
        held = state.integral.raw();
      }
      if (first_saturated > 0) {
        if (state.integral.raw() != held) ++moved_after_hold;
        if (duty.raw() != sign * 28672) ++wrong_duty;  // 0.875 · 32768
      }
    }
    // Verify
    VT_EXPECT_EQ(first_saturated, 469);
    VT_EXPECT_EQ(moved_after_hold, 0);
    VT_EXPECT_EQ(wrong_duty, 0);
    VT_EXPECT_NEAR(state.integral.ToDouble(), sg * 0.3752, 469 * (kQ24 / 2 + kQ31));

    // Exercise: the error reverses to 0.04 rad the other way. P = −0.02, and the held
    // integral takes one step of −3.2e-5: 0.375168 − 0.02 = 0.355168, unsaturated on the
    // very first tick (a wound-up integral at 0.6 would give 0.58).
    const Duty duty =
        loop.Update(Angle::Quantize(0.2 - 0.04 * sg), AngularVelocity{}, motor);
    // Verify
    VT_EXPECT_TRUE(!loop.status().saturated);
    VT_EXPECT_NEAR(duty.ToDouble(), sg * 0.355168, kQ15 / 2 + 470 * (kQ24 / 2 + kQ31));
  }
}

MJC_VECTOR_TEST(PositionLoop, IntegralClampsAtIntegralLimit) {
  for (const int sign : kSigns) {
    // Setup: P = 0.1 alone never saturates; I would grow 1e-3 a tick without bound.
    const double sg = static_cast<double>(sign);
    const PositionLoopConfig config =
        MakeConfig({0.1, 10.0, 0.0, 0.0, 0.9, 0.3, 1.0, 10000});
    PositionLoop::State state;
    PositionLoop loop(&config, &state);
    // Exercise
    Duty duty;
    bool ever_saturated = false;
    double largest = 0;
    for (int t = 0; t < 20000; ++t) {
      duty = loop.Update(Angle::Quantize(sg), AngularVelocity{}, Angle{});
      ever_saturated = ever_saturated || loop.status().saturated;
      largest = MaxD(largest, AbsD(state.integral.ToDouble()));
    }
    // Verify: I is exactly ±integral_limit (0.29998779296875 = 9830/32768), and the duty
    // is kp·1 + I = 0.100006103515625 + 0.29998779296875 = 13107/32768.
    VT_EXPECT_EQ(state.integral.raw(), sign * 9830 * 512);
    VT_EXPECT_TRUE(largest <= 9830.0 * kQ15);
    VT_EXPECT_EQ(duty.raw(), sign * 13107);
    VT_EXPECT_TRUE(!ever_saturated);
  }
}

MJC_VECTOR_TEST(PositionLoop, IntegrationStopsExactlyAtTheLimit) {
  // Setup: max_duty 0.5, kp = 1, ki = 100 per rad·s (0.01 a tick per rad).
  const PositionLoopConfig config =
      MakeConfig({1.0, 100.0, 0.0, 0.0, 0.5, 0.5, 1.0, 10000});
  for (const int sign : kSigns) {
    // P exactly at the limit with the error pushing outward: no integration at all.
    {
      PositionLoop::State state;
      PositionLoop loop(&config, &state);
      Duty duty;
      for (int t = 0; t < 1000; ++t) {
        duty = loop.Update(Angle::FromRaw(sign * (1 << 23)), AngularVelocity{}, Angle{});
      }
      VT_EXPECT_EQ(state.integral.raw(), 0);
      VT_EXPECT_EQ(duty.raw(), sign * 16384);
      VT_EXPECT_TRUE(!loop.status().saturated);  // at the limit is not beyond it
    }
    // One Angle LSB inside the limit: the first tick integrates 0.01·(0.5 − 2^-24),
    // after which P + I is beyond the limit and I holds.
    {
      PositionLoop::State state;
      PositionLoop loop(&config, &state);
      Duty duty;
      for (int t = 0; t < 1000; ++t) {
        duty = loop.Update(Angle::FromRaw(sign * ((1 << 23) - 1)), AngularVelocity{},
                           Angle{});
      }
      VT_EXPECT_NEAR(state.integral.ToDouble(), sign * 0.01 * (0.5 - kQ24),
                     kQ24 / 2 + kQ31 * 0.5);
      VT_EXPECT_EQ(duty.raw(), sign * 16384);
      VT_EXPECT_TRUE(loop.status().saturated);
    }
  }
}

MJC_VECTOR_TEST(PositionLoop, IntegratesWhenErrorPullsBackFromSaturation) {
  // Setup: ki = 100 (0.01 a tick per rad) and kff = 1: a setpoint velocity of ±1 rad/s
  // puts ±1.0 of feed-forward beyond max_duty 0.9 on its own.
  const PositionLoopConfig config =
      MakeConfig({0.0, 100.0, 0.0, 1.0, 0.9, 0.9, 1.0, 10000});
  for (const int sign : kSigns) {
    const double sg = static_cast<double>(sign);
    const AngularVelocity v = AngularVelocity::Quantize(sg);
    // Error against the saturation: I falls 1e-3 a tick; after 200 ticks I = −0.2 and
    // the duty 0.8 is inside the limit again.
    {
      PositionLoop::State state;
      PositionLoop loop(&config, &state);
      Duty duty;
      for (int t = 0; t < 200; ++t)
        duty = loop.Update(Angle::Quantize(-0.1 * sg), v, Angle{});
      VT_EXPECT_NEAR(state.integral.ToDouble(), -0.2 * sg, 200 * (kQ24 / 2 + kQ31 * 0.1));
      VT_EXPECT_NEAR(duty.ToDouble(), 0.8 * sg, kQ15 / 2 + 200 * (kQ24 / 2 + kQ31 * 0.1));
      VT_EXPECT_TRUE(!loop.status().saturated);
    }
    // Error into the saturation: nothing integrates.
    {
      PositionLoop::State state;
      PositionLoop loop(&config, &state);
      for (int t = 0; t < 200; ++t) loop.Update(Angle::Quantize(0.1 * sg), v, Angle{});
      VT_EXPECT_EQ(state.integral.raw(), 0);
      VT_EXPECT_TRUE(loop.status().saturated);
    }
  }
}

MJC_VECTOR_TEST(PositionLoop, ValidateRefusesEachBadField) {
  const PositionLoopConfig good =
      MakeConfig({8.0, 40.0, 0.2, 0.3, 0.9, 0.3, 0.05, 10000});
  VT_EXPECT_TRUE(mjc::Validate(good) == PositionLoopError::kOk);
  VT_EXPECT_TRUE(mjc::Validate(PositionLoopConfig{}) == PositionLoopError::kOk);

  struct Case {
    void (*mutate)(PositionLoopConfig&);
    PositionLoopError want;
  };
  const Case kCases[] = {
      {[](PositionLoopConfig& c) { c.kp = Kp::FromRaw(-1); },
       PositionLoopError::kNegativeGain},
      {[](PositionLoopConfig& c) { c.ki = Ki::FromRaw(-1); },
       PositionLoopError::kNegativeGain},
      {[](PositionLoopConfig& c) { c.kd = Kd::FromRaw(-1); },
       PositionLoopError::kNegativeGain},
      {[](PositionLoopConfig& c) { c.kp = Kp::Max(); }, PositionLoopError::kOk},
      {[](PositionLoopConfig& c) { c.kff = Kff::Quantize(-3.0); },
       PositionLoopError::kOk},
      {[](PositionLoopConfig& c) { c.max_duty = Duty{}; },
       PositionLoopError::kDutyLimitOutOfRange},
      {[](PositionLoopConfig& c) { c.max_duty = Duty::FromDouble(-0.5); },
       PositionLoopError::kDutyLimitOutOfRange},
      {[](PositionLoopConfig& c) {
         c.max_duty = Duty::Epsilon();
         c.integral_limit = Duty{};
       },
       PositionLoopError::kOk},
      {[](PositionLoopConfig& c) { c.integral_limit = -Duty::Epsilon(); },
       PositionLoopError::kIntegralLimitOutOfRange},
      {[](PositionLoopConfig& c) { c.integral_limit = c.max_duty + Duty::Epsilon(); },
       PositionLoopError::kIntegralLimitOutOfRange},
      {[](PositionLoopConfig& c) { c.integral_limit = c.max_duty; },
       PositionLoopError::kOk},
      {[](PositionLoopConfig& c) { c.integral_limit = Duty{}; }, PositionLoopError::kOk},
      {[](PositionLoopConfig& c) { c.velocity_filter = Beta{}; },
       PositionLoopError::kFilterOutOfRange},
      {[](PositionLoopConfig& c) { c.velocity_filter = -Beta::FromDouble(0.5); },
       PositionLoopError::kFilterOutOfRange},
      {[](PositionLoopConfig& c) { c.velocity_filter = Beta(1) + Beta::Epsilon(); },
       PositionLoopError::kFilterOutOfRange},
      {[](PositionLoopConfig& c) { c.velocity_filter = Beta(1); },
       PositionLoopError::kOk},
      {[](PositionLoopConfig& c) { c.velocity_filter = Beta::Epsilon(); },
       PositionLoopError::kOk},
      {[](PositionLoopConfig& c) { c.tick_hz = 99; },
       PositionLoopError::kTickRateOutOfRange},
      {[](PositionLoopConfig& c) { c.tick_hz = 100001; },
       PositionLoopError::kTickRateOutOfRange},
      {[](PositionLoopConfig& c) { c.tick_hz = 0; },
       PositionLoopError::kTickRateOutOfRange},
      {[](PositionLoopConfig& c) { c.tick_hz = 100; }, PositionLoopError::kOk},
      {[](PositionLoopConfig& c) { c.tick_hz = 100000; }, PositionLoopError::kOk},
  };
  for (const Case& c : kCases) {
    PositionLoopConfig config = good;
    c.mutate(config);
    VT_EXPECT_EQ(static_cast<int>(mjc::Validate(config)), static_cast<int>(c.want));
  }
  // The codes are stable numbers.
  VT_EXPECT_EQ(static_cast<int>(PositionLoopError::kNegativeGain), 1);
  VT_EXPECT_EQ(static_cast<int>(PositionLoopError::kDutyLimitOutOfRange), 2);
  VT_EXPECT_EQ(static_cast<int>(PositionLoopError::kIntegralLimitOutOfRange), 3);
  VT_EXPECT_EQ(static_cast<int>(PositionLoopError::kFilterOutOfRange), 4);
  VT_EXPECT_EQ(static_cast<int>(PositionLoopError::kTickRateOutOfRange), 5);
}

}  // namespace
