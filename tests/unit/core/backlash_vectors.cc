// The backlash play operator and its inverse against a double-precision reference of
// the paper's eq. (4), with and without the cable sliding under the spring (backlash.h).
// Bound: the fixed-point output is within 1 LSB of the reference fed the same
// (quantised) inputs — each band edge α(θ_m − c) and the slip deflection τ_f/K are
// rounded once (≤ 0.5 LSB) and the clamps only ever select the held value, a slip
// bound or an edge.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>

#include "mjc/core/backlash.h"
#include "vector_test.h"

namespace {

using mjc::Angle;
using mjc::BacklashConfig;
using mjc::BacklashModel;
using mjc::Scale;
using mjc::Stiffness;
using mjc::Torque;

constexpr double kLsb = 1.0 / (1 << 24);

// Double-precision play operator (eq. 4); `slip` = τ_f/K, infinite: never slides.
struct ReferencePlay {
  double alpha, c_r, c_l, out;
  double slip = std::numeric_limits<double>::infinity();
  double Update(double motor, double joint = 0) {
    out = std::min(std::max(out, joint - slip), joint + slip);  // the cable slides
    const double lo = alpha * (motor - c_r);
    const double hi = alpha * (motor - c_l);
    out = out < lo ? lo : (out > hi ? hi : out);
    return out;
  }
};

BacklashConfig MakeConfig(double alpha, double c_r_deg, double c_l_deg) {
  BacklashConfig c;
  c.alpha = Scale::Quantize(alpha);
  c.c_right = Angle::Quantize(c_r_deg * std::numbers::pi / 180.0);
  c.c_left = Angle::Quantize(c_l_deg * std::numbers::pi / 180.0);
  return c;
}

// Runs model and reference over `motor(i)` for n ticks; returns the worst error in LSB.
template <class Motor>
double WorstError(const BacklashConfig& config, int n, Motor motor) {
  BacklashModel::State state;
  BacklashModel model(&config, &state);
  const Angle first = motor(0);
  model.Reset(first, Angle{});
  ReferencePlay ref{config.alpha.ToDouble(), config.c_right.ToDouble(),
                    config.c_left.ToDouble(), state.output.ToDouble()};
  double worst = 0;
  for (int i = 1; i < n; ++i) {
    const Angle m = motor(i);
    const double got = model.Update(m, Angle{}).ToDouble();
    const double want = ref.Update(m.ToDouble());
    const double e = std::fabs(got - want) / kLsb;
    worst = e > worst ? e : worst;
    ref.out = got;  // follow the model's state so errors do not compound
  }
  return worst;
}

MJC_VECTOR_TEST(Backlash, IncreasingSinusoidWithinOneLsb) {
  const BacklashConfig config = MakeConfig(1.0, 1.1, -0.9);
  // The paper's calibration input: amplitude rising 0 → 30° over 10 cycles at 0.5 Hz.
  const double worst = WorstError(config, 200000, [](int i) {
    const double t = i * 1e-4;
    const double amp = (30.0 * std::numbers::pi / 180.0) * (t / 20.0);
    return Angle::Quantize(amp * std::sin(2 * std::numbers::pi * 0.5 * t));
  });
  VT_EXPECT_LE(worst, 1.0);
}

MJC_VECTOR_TEST(Backlash, LongRandomWalkWithNonUnitAlpha) {
  const BacklashConfig config = MakeConfig(1.37, 0.8, -1.6);
  mjc::vt::Rng rng(101);
  std::int32_t pos = 0;
  const double worst = WorstError(config, 200000, [&](int) {
    pos += rng.NextI32() >> 19;  // steps up to ±4096 LSB, reversals every few ticks
    return Angle::FromRaw(pos);
  });
  VT_EXPECT_LE(worst, 1.0);
}

MJC_VECTOR_TEST(Backlash, ReversalInsideDeadBandHolds) {
  const BacklashConfig config = MakeConfig(1.0, 1.0, -1.0);  // 2° slack
  BacklashModel::State state;
  BacklashModel model(&config, &state);
  model.Reset(Angle{}, Angle{});
  // Drive positive to 10°: the output follows θ_m − c_r.
  Angle out;
  for (int i = 0; i <= 1000; ++i)
    out = model.Update(Angle::Quantize(i * 0.01 * std::numbers::pi / 180), Angle{});
  VT_EXPECT_NEAR(out.ToDouble(), 9.0 * std::numbers::pi / 180, 2 * kLsb);
  // Back by 1.5° (less than the 2° slack): the output holds.
  for (int i = 1000; i >= 850; --i) {
    VT_EXPECT_TRUE(
        model.Update(Angle::Quantize(i * 0.01 * std::numbers::pi / 180), Angle{}) == out);
  }
  // Back past the slack: it follows θ_m − c_l.
  for (int i = 850; i >= 500; --i)
    out = model.Update(Angle::Quantize(i * 0.01 * std::numbers::pi / 180), Angle{});
  VT_EXPECT_NEAR(out.ToDouble(), 6.0 * std::numbers::pi / 180, 2 * kLsb);
}

MJC_VECTOR_TEST(Backlash, ResetClampsJointIntoBand) {
  const BacklashConfig config = MakeConfig(1.0, 1.0, -1.0);
  BacklashModel::State state;
  BacklashModel model(&config, &state);
  const Angle motor = Angle::Quantize(0.2);
  VT_EXPECT_TRUE(model.Reset(motor, Angle::Quantize(0.2)) == Angle::Quantize(0.2));
  VT_EXPECT_TRUE(model.Reset(motor, Angle::Quantize(1.0)) == model.UpperEdge(motor));
  VT_EXPECT_TRUE(model.Reset(motor, Angle::Quantize(-1.0)) == model.LowerEdge(motor));
}

MJC_VECTOR_TEST(Backlash, InverseThenForwardTracksWantedAngle) {
  // Commanding the motor through the inverse model makes the forward model's output
  // follow the wanted cable-side angle, in both directions, with the slack taken up.
  const BacklashConfig config = MakeConfig(1.2, 1.3, -0.7);
  mjc::InverseBacklash::State inv_state;
  mjc::InverseBacklash inverse(&config, &inv_state);
  BacklashModel::State state;
  BacklashModel model(&config, &state);
  double worst = 0;
  for (int i = 0; i < 40000; ++i) {
    const Angle wanted =
        Angle::Quantize(0.3 * std::sin(2 * std::numbers::pi * 0.5 * i * 1e-4));
    const Angle motor = inverse.Command(wanted);
    const Angle out = i == 0 ? model.Reset(motor, wanted) : model.Update(motor, wanted);
    if (i > 10) {
      const double e = std::fabs(out.ToDouble() - wanted.ToDouble()) / kLsb;
      worst = e > worst ? e : worst;
    }
  }
  // α·(1/α) and two roundings: a few LSB, not the 2° (≈ 585,000 LSB) of uncompensated
  // slack.
  VT_EXPECT_LE(worst, 8.0);
}

MJC_VECTOR_TEST(Backlash, ValidateRefusesBadConfigs) {
  VT_EXPECT_TRUE(mjc::Validate(MakeConfig(1.0, 1.0, -1.0)) ==
                 mjc::BacklashConfigError::kOk);
  VT_EXPECT_TRUE(mjc::Validate(MakeConfig(0.0, 1.0, -1.0)) ==
                 mjc::BacklashConfigError::kAlphaOutOfRange);
  VT_EXPECT_TRUE(mjc::Validate(MakeConfig(-1.0, 1.0, -1.0)) ==
                 mjc::BacklashConfigError::kAlphaOutOfRange);
  // 1/α must fit Scale too: α = 1/8 would make the inverse saturate at 8 − 2^-28.
  VT_EXPECT_TRUE(mjc::Validate(MakeConfig(0.125, 1.0, -1.0)) ==
                 mjc::BacklashConfigError::kAlphaOutOfRange);
  VT_EXPECT_TRUE(mjc::Validate(MakeConfig(0.1250001, 1.0, -1.0)) ==
                 mjc::BacklashConfigError::kOk);
  VT_EXPECT_TRUE(mjc::Validate(MakeConfig(7.9999999, 1.0, -1.0)) ==
                 mjc::BacklashConfigError::kOk);
  VT_EXPECT_TRUE(mjc::Validate(MakeConfig(1.0, 40.0, -1.0)) ==
                 mjc::BacklashConfigError::kOffsetOutOfRange);
  VT_EXPECT_TRUE(mjc::Validate(MakeConfig(1.0, -1.0, 1.0)) ==
                 mjc::BacklashConfigError::kLeftAboveRight);
  BacklashConfig friction = MakeConfig(1.0, 1.0, -1.0);
  friction.cable_friction = mjc::kMaxCableFriction;
  VT_EXPECT_TRUE(mjc::Validate(friction) == mjc::BacklashConfigError::kOk);
  friction.cable_friction = mjc::kMaxCableFriction + Torque::Epsilon();
  VT_EXPECT_TRUE(mjc::Validate(friction) ==
                 mjc::BacklashConfigError::kFrictionOutOfRange);
  friction.cable_friction = -Torque::Epsilon();
  VT_EXPECT_TRUE(mjc::Validate(friction) ==
                 mjc::BacklashConfigError::kFrictionOutOfRange);
}

// A stiff joint held still while the motor pulls the cable to 20° and comes back: the
// spring (K = 0.5 N·m/rad) pulls the cable side after the receding pulley until its
// torque is the sheath's τ_f = 0.1 N·m (θ̃ = τ_f/K = 0.2 rad), where the cable stops
// and the pulley goes on through the slack. Without τ_f the cable stays at 19°.
MJC_VECTOR_TEST(Backlash, CableSlidesBackUntilTheSpringTorqueIsTheFriction) {
  BacklashConfig config = MakeConfig(1.0, 1.0, -1.0);  // 2° slack
  config.cable_friction = Torque::Quantize(0.1);
  const Stiffness k_sea = Stiffness::Quantize(0.5);
  const auto deg = [](double d) { return Angle::Quantize(d * std::numbers::pi / 180); };
  for (const bool modelled : {true, false}) {
    BacklashConfig c = config;
    if (!modelled) c.cable_friction = Torque{};
    BacklashModel::State state;
    BacklashModel model(&c, &state);
    model.Configure(k_sea);
    model.Reset(Angle{}, Angle{});
    const Angle joint{};  // held
    Angle out;
    for (int i = 0; i <= 2000; ++i) out = model.Update(deg(i * 0.01), joint);
    VT_EXPECT_NEAR(out.ToDouble(), 19.0 * std::numbers::pi / 180, 2 * kLsb);
    // Back by 1°, inside the slack: a held cable holds, a sliding one follows the
    // pulley's edge (its spring torque, 0.5 × 0.33 N·m, is above τ_f).
    for (int i = 2000; i >= 1900; --i) out = model.Update(deg(i * 0.01), joint);
    const double back_1deg = modelled ? 18.0 : 19.0;
    VT_EXPECT_NEAR(out.ToDouble(), back_1deg * std::numbers::pi / 180, 2 * kLsb);
    // Back to 12°: the sliding cable stopped at τ_f/K = 0.2 rad (11.46°), inside the
    // band [11°, 13°]; the held one was pushed down by the band's upper edge, 13°.
    for (int i = 1900; i >= 1200; --i) out = model.Update(deg(i * 0.01), joint);
    if (modelled) {
      VT_EXPECT_NEAR(out.ToDouble(), 0.2, 2 * kLsb);
      VT_EXPECT_NEAR(Mul<Torque>(k_sea, out - joint).ToDouble(), 0.1, 4 * kLsb);
    } else {
      VT_EXPECT_NEAR(out.ToDouble(), 13.0 * std::numbers::pi / 180, 2 * kLsb);
    }
  }
}

// The slip deflection against τ_f/K in double, its "never slides" cases, and a
// random walk of motor and joint with the cable sliding, against the reference.
MJC_VECTOR_TEST(Backlash, SlidingCableWithinOneLsbOfReference) {
  BacklashConfig config = MakeConfig(1.25, 1.1, -0.9);
  config.cable_friction = Torque::Quantize(0.3);
  const Stiffness k_sea = Stiffness::Quantize(1.152);
  BacklashModel::State state;
  BacklashModel model(&config, &state);
  VT_EXPECT_TRUE(model.slip() == BacklashModel::kNoSlip);  // until configured
  model.Configure(k_sea);
  const double slip = config.cable_friction.ToDouble() / k_sea.ToDouble();
  VT_EXPECT_NEAR(model.slip().ToDouble(), slip, 0.5 * kLsb);
  {
    BacklashConfig none = config;
    none.cable_friction = Torque{};
    BacklashModel::State s;
    BacklashModel m(&none, &s);
    m.Configure(k_sea);
    VT_EXPECT_TRUE(m.slip() == BacklashModel::kNoSlip);
    BacklashModel strong(&config, &s);  // τ_f/K = 0.3/0.001 rad: beyond any reach
    strong.Configure(Stiffness::Quantize(0.001));
    VT_EXPECT_TRUE(strong.slip() == BacklashModel::kNoSlip);
  }
  // The joint follows the cable side through a stiff attachment (a fifth of its
  // travel) plus a random wobble; the motor's amplitude grows so the spring's torque
  // crosses τ_f on every reversal from the first few cycles on.
  mjc::vt::Rng rng(7);
  model.Reset(Angle{}, Angle{});
  ReferencePlay ref{config.alpha.ToDouble(), config.c_right.ToDouble(),
                    config.c_left.ToDouble(), 0.0, slip};
  double worst = 0;
  int sliding = 0;
  for (int i = 1; i < 100000; ++i) {
    const double t = i * 1e-4;
    const double amp = 0.8 * t / 10.0;
    const Angle motor = Angle::Quantize(amp * std::sin(2 * std::numbers::pi * t));
    const Angle joint = Angle::FromRaw(
        Angle::Quantize(0.2 * state.output.ToDouble()).raw() + (rng.NextI32() >> 22));
    const double before = state.output.ToDouble();
    const double got = model.Update(motor, joint).ToDouble();
    const double want = ref.Update(motor.ToDouble(), joint.ToDouble());
    worst = std::max(worst, std::fabs(got - want) / kLsb);
    if (std::fabs(before - joint.ToDouble()) > slip && got != before &&
        got > model.LowerEdge(motor).ToDouble() &&
        got < model.UpperEdge(motor).ToDouble()) {
      ++sliding;  // moved by the spring, not by the pulley
    }
    ref.out = got;
  }
  VT_EXPECT_LE(worst, 1.0);
  VT_EXPECT_TRUE(sliding > 100);
}

}  // namespace
