// The attachment model (attachment_model.h) against a double-precision backward Euler
// of b·θ̇ = K(θ̃ − θ) − k·θ + c written from the header's equation, its coefficients
// against their formulas, and its limits.
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <initializer_list>
#include <numbers>

#include "mjc/core/attachment_model.h"
#include "vector_test.h"

namespace {

using mjc::Angle;
using mjc::AttachmentModel;
using mjc::AttachmentParams;
using mjc::Damping;
using mjc::ModelAngle;
using mjc::Stiffness;

constexpr double kModelLsb = 1.0 / (1 << 27);
constexpr double kCoefficientLsb = 1.0 / (1 << 30);
constexpr std::uint32_t kTickHz = 10000;

// The paper's spring and subject 2's attachment.
constexpr Stiffness kSea = Stiffness::FromDouble(0.63);
constexpr AttachmentParams kSubject2{Stiffness::FromDouble(5.5),
                                     Damping::FromDouble(0.29)};

// A cable side that moves like the one behind the slack: a 0.5 Hz sine of 0.3 rad
// that stops for 40 ms at each reversal (the cable crossing its slack), with the motor
// encoder's fine steps.
Angle CableAt(int tick) {
  const double t = tick / double(kTickHz);
  const double phase = std::fmod(t, 1.0);  // half a cycle a second
  const double held = phase < 0.04 ? 0.0 : (phase - 0.04) / 0.96;
  const double sign = std::fmod(t, 2.0) < 1.0 ? 1.0 : -1.0;
  return Angle::Quantize(0.1 + sign * 0.3 * std::sin(std::numbers::pi * held));
}

// The header's recursion in double: T = β·θ̃ + offset, θ += g·(T − θ).
struct DoubleModel {
  double beta, gain, offset, angle;
  DoubleModel(double k, double b, double joint, double cable) {
    const double sea = kSea.ToDouble();
    beta = sea / (sea + k);
    gain = (sea + k) / (sea + k + b * kTickHz);
    angle = joint;
    offset = joint - beta * cable;
  }
  double Step(double cable) {
    const double before = angle;
    angle += gain * (beta * cable + offset - angle);
    return angle - before;
  }
};

MJC_VECTOR_TEST(AttachmentModel, CoefficientsAreTheirFormulas) {
  AttachmentModel model;
  VT_EXPECT_TRUE(model.Configure(kSea, kSubject2, kTickHz));
  const double sea = kSea.ToDouble(), k = kSubject2.stiffness.ToDouble(),
               b = kSubject2.damping.ToDouble();
  VT_EXPECT_NEAR(model.beta().ToDouble(), sea / (sea + k), kCoefficientLsb);
  VT_EXPECT_NEAR(model.gain().ToDouble(), (sea + k) / (sea + k + b * kTickHz),
                 kCoefficientLsb);
}

MJC_VECTOR_TEST(AttachmentModel, FollowsTheDoubleRecursionWithinItsRounding) {
  AttachmentModel model;
  VT_EXPECT_TRUE(model.Configure(kSea, kSubject2, kTickHz));
  const Angle joint = Angle::Quantize(0.08);
  model.Reset(joint, CableAt(0));
  DoubleModel ref(kSubject2.stiffness.ToDouble(), kSubject2.damping.ToDouble(),
                  joint.ToDouble(), CableAt(0).ToDouble());
  // Each step rounds to ModelAngle (≤ 0.5 LSB) and the model forgets an old error at
  // the rate g, so the state stays within 0.5/g LSB of the exact recursion, plus the
  // coefficients' own rounding.
  const double bound = (0.5 / ref.gain + 4) * kModelLsb;
  double worst = 0, travel = 0;
  ModelAngle previous = model.angle();
  for (int i = 1; i <= 40000; ++i) {
    const Angle cable = CableAt(i);
    const std::int32_t step = model.ISR_Step(cable);
    ref.Step(cable.ToDouble());
    VT_EXPECT_EQ(step, model.angle().raw() - previous.raw());
    previous = model.angle();
    travel = std::fmax(travel, std::fabs(ref.angle - 0.08));
    worst = std::fmax(worst, std::fabs(model.angle().ToDouble() - ref.angle));
  }
  VT_EXPECT_LE(worst, bound);
  VT_EXPECT_TRUE(travel > 0.01);  // the model did move (β·0.6 rad swings)
}

MJC_VECTOR_TEST(AttachmentModel, StartsAtRestWhereTheJointIs) {
  AttachmentModel model;
  VT_EXPECT_TRUE(model.Configure(kSea, kSubject2, kTickHz));
  const Angle joint = Angle::Quantize(-0.2), cable = Angle::Quantize(0.05);
  model.Reset(joint, cable);
  for (int i = 0; i < 1000; ++i) VT_EXPECT_EQ(model.ISR_Step(cable), 0);
  VT_EXPECT_NEAR(model.angle().ToDouble(), joint.ToDouble(), kModelLsb);
}

MJC_VECTOR_TEST(AttachmentModel, ANewFitKeepsTheNextStep) {
  // On a ramp, the step after a new fit is the one the old coefficients would have
  // made (attachment_model.h: no jump in the model's velocity).
  AttachmentModel model, unchanged;
  VT_EXPECT_TRUE(model.Configure(kSea, kSubject2, kTickHz));
  VT_EXPECT_TRUE(unchanged.Configure(kSea, kSubject2, kTickHz));
  model.Reset(Angle{}, Angle{});
  unchanged.Reset(Angle{}, Angle{});
  Angle cable;
  for (int i = 1; i <= 3000; ++i) {
    cable = Angle::FromRaw(i * 3355);  // 2 rad/s
    model.ISR_Step(cable);
    unchanged.ISR_Step(cable);
  }
  const AttachmentParams other{Stiffness::FromDouble(3.0), Damping::FromDouble(0.15)};
  VT_EXPECT_TRUE(model.Configure(kSea, other, kTickHz));
  const std::int32_t step = model.ISR_Step(cable);
  const std::int32_t want = unchanged.ISR_Step(cable);
  VT_EXPECT_TRUE(want > 1000);  // the model was moving
  VT_EXPECT_LE(std::abs(step - want), 2);
}

MJC_VECTOR_TEST(AttachmentModel, RefusesNegativeParamsAndKeepsItsCoefficients) {
  AttachmentModel model;
  VT_EXPECT_TRUE(model.Configure(kSea, kSubject2, kTickHz));
  const auto beta = model.beta(), gain = model.gain();
  VT_EXPECT_TRUE(!model.Configure(
      kSea, {Stiffness::FromDouble(-0.1), Damping::FromDouble(0.2)}, kTickHz));
  VT_EXPECT_TRUE(!model.Configure(
      kSea, {Stiffness::FromDouble(4.0), Damping::FromDouble(-0.01)}, kTickHz));
  VT_EXPECT_TRUE(!model.Configure(Stiffness{}, kSubject2, kTickHz));
  VT_EXPECT_TRUE(model.beta() == beta && model.gain() == gain);
}

MJC_VECTOR_TEST(AttachmentModel, NoDampingFollowsTheCableAtOnce) {
  // b = 0: g = 1, the joint where the spring and the attachment balance.
  AttachmentModel model;
  VT_EXPECT_TRUE(model.Configure(kSea, {Stiffness::FromDouble(5.5), Damping{}}, kTickHz));
  VT_EXPECT_EQ(model.gain().raw(), 1 << 30);
  model.Reset(Angle{}, Angle{});
  model.ISR_Step(Angle::Quantize(0.5));
  VT_EXPECT_NEAR(model.angle().ToDouble(), 0.5 * 0.63 / (0.63 + 5.5), 2 * kModelLsb);
}

MJC_VECTOR_TEST(AttachmentModel, StaysInRangeAtTheExtremes) {
  // The largest cable sides, either way, with the fastest model: the state stays
  // within ±6 rad and every step equals the state's change (no wrap-around).
  AttachmentModel model;
  VT_EXPECT_TRUE(
      model.Configure(Stiffness::FromDouble(100), {Stiffness{}, Damping{}}, kTickHz));
  model.Reset(Angle::Max(), Angle::Min());
  for (const Angle cable : {Angle::Max(), Angle::Min(), Angle::Max(), Angle{}}) {
    const std::int64_t before = model.angle().raw();
    const std::int32_t step = model.ISR_Step(cable);
    VT_EXPECT_EQ(std::int64_t{model.angle().raw()}, before + step);
    VT_EXPECT_LE(std::fabs(model.angle().ToDouble()), 6.0);
  }
}

}  // namespace
