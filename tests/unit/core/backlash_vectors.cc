// The backlash play operator and its inverse against a double-precision reference of
// the paper's eq. (4). Bound: the fixed-point output is within 1 LSB of the reference
// fed the same (quantised) inputs — each band edge α(θ_m − c) is rounded once (≤ 0.5
// LSB) and the clamp only ever selects the held value or an edge.
#include <cmath>
#include <cstdint>
#include <numbers>

#include "mjc/core/backlash.h"
#include "vector_test.h"

namespace {

using mjc::Angle;
using mjc::BacklashConfig;
using mjc::BacklashModel;
using mjc::Scale;

constexpr double kLsb = 1.0 / (1 << 24);

// Double-precision play operator (eq. 4).
struct ReferencePlay {
  double alpha, c_r, c_l, out;
  double Update(double motor) {
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
    const double got = model.Update(m).ToDouble();
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
    out = model.Update(Angle::Quantize(i * 0.01 * std::numbers::pi / 180));
  VT_EXPECT_NEAR(out.ToDouble(), 9.0 * std::numbers::pi / 180, 2 * kLsb);
  // Back by 1.5° (less than the 2° slack): the output holds.
  for (int i = 1000; i >= 850; --i) {
    VT_EXPECT_TRUE(model.Update(Angle::Quantize(i * 0.01 * std::numbers::pi / 180)) ==
                   out);
  }
  // Back past the slack: it follows θ_m − c_l.
  for (int i = 850; i >= 500; --i)
    out = model.Update(Angle::Quantize(i * 0.01 * std::numbers::pi / 180));
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
  state.Clear();
  const Angle mid = model.Update(motor);  // no joint reading: middle of the band
  VT_EXPECT_NEAR(mid.ToDouble(), 0.2, 2 * kLsb);
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
    const Angle out = i == 0 ? model.Reset(motor, wanted) : model.Update(motor);
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
}

}  // namespace
