// Fixed-point arithmetic against a double-precision reference, over the whole raw range
// of each format and at its saturation edges. These vectors run on the host and on the
// Cortex-M4 under QEMU.
//
// Error bounds, in LSBs of the result format:
//   add, sub, negate, abs, integer scaling, widening casts: exact (0 LSB);
//   products (Mul), narrowing casts, Quantize, Divide:       <= 0.5 LSB;
//   a saturated result equals the format's Max() or Min() exactly.
// The reference is double arithmetic; where its own rounding matters (products of two
// 31-bit values need 62 bits, a double holds 53) the bound adds 2^-52 relative, far
// below an output LSB in these formats.
#include <cstdint>
#include <limits>

#include "mjc/core/fixed.h"
#include "mjc/core/quantities.h"
#include "vector_test.h"

namespace {

using mjc::Fixed;
using mjc::vt::Rng;

constexpr int kRandomSamples = 20000;

template <class T>
constexpr double Lsb() {
  return T::Epsilon().ToDouble();
}

// The double value a result of format T must equal, after saturation to T's range.
template <class T>
double SaturatedReference(double exact) {
  const double hi = T::Max().ToDouble();
  const double lo = T::Min().ToDouble();
  return exact > hi ? hi : (exact < lo ? lo : exact);
}

// |got - exact| in LSBs of T, with exact saturated to T's range first.
template <class T>
double ErrorLsb(T got, double exact) {
  const double ref = SaturatedReference<T>(exact);
  const double d = got.ToDouble() - ref;
  return (d < 0 ? -d : d) / Lsb<T>();
}

template <class T>
double ReferenceSlackLsb(double exact) {
  const double a = exact < 0 ? -exact : exact;
  return a * 2.3e-16 / Lsb<T>();  // 2^-52 relative
}

// Edge raws every binary operation is tried with, besides random ones.
template <class Rep>
constexpr Rep kEdges[] = {std::numeric_limits<Rep>::min(),
                          static_cast<Rep>(std::numeric_limits<Rep>::min() + 1),
                          static_cast<Rep>(-2),
                          static_cast<Rep>(-1),
                          static_cast<Rep>(0),
                          static_cast<Rep>(1),
                          static_cast<Rep>(2),
                          static_cast<Rep>(std::numeric_limits<Rep>::max() - 1),
                          std::numeric_limits<Rep>::max(),
                          static_cast<Rep>(std::numeric_limits<Rep>::max() / 2),
                          static_cast<Rep>(std::numeric_limits<Rep>::min() / 2)};

template <class Rep>
Rep RandomRaw(Rng& rng) {
  if constexpr (sizeof(Rep) == 2) {
    return rng.NextI16();
  } else if constexpr (sizeof(Rep) == 4) {
    // Half the samples full-range, half small-magnitude so that results which do not
    // saturate are well covered too.
    const std::int32_t r = rng.NextI32();
    return (rng.Next() & 1u) ? r : static_cast<std::int32_t>(r >> (rng.Next() % 31u));
  } else {
    return rng.NextI64();
  }
}

// Calls f(a, b) over edge x edge pairs and kRandomSamples random pairs.
template <class A, class B, class F>
void ForPairs(std::uint64_t seed, F f) {
  for (auto ra : kEdges<typename A::rep>) {
    for (auto rb : kEdges<typename B::rep>) f(A::FromRaw(ra), B::FromRaw(rb));
  }
  Rng rng(seed);
  for (int i = 0; i < kRandomSamples; ++i) {
    f(A::FromRaw(RandomRaw<typename A::rep>(rng)),
      B::FromRaw(RandomRaw<typename B::rep>(rng)));
  }
}

template <class T>
void CheckAddSub(mjc::vt::Context& vt_context, std::uint64_t seed) {
  double worst = 0;
  ForPairs<T, T>(seed, [&](T a, T b) {
    const double sum = a.ToDouble() + b.ToDouble();  // exact: < 2^33 LSBs for 32-bit reps
    const double diff = a.ToDouble() - b.ToDouble();
    const double e1 = ErrorLsb(a + b, sum);
    const double e2 = ErrorLsb(a - b, diff);
    worst = e1 > worst ? e1 : worst;
    worst = e2 > worst ? e2 : worst;
  });
  VT_EXPECT_EQ(worst, 0.0);
}

MJC_VECTOR_TEST(FixedAddSub, ExactOrSaturatedQ7Dot24) {
  CheckAddSub<mjc::Angle>(vt_context, 11);
}
MJC_VECTOR_TEST(FixedAddSub, ExactOrSaturatedQ0Dot15Int16) {
  CheckAddSub<mjc::Duty>(vt_context, 12);
}

MJC_VECTOR_TEST(FixedAddSub, SaturationEdges) {
  using mjc::Angle;
  VT_EXPECT_TRUE(Angle::Max() + Angle::Epsilon() == Angle::Max());
  VT_EXPECT_TRUE(Angle::Min() - Angle::Epsilon() == Angle::Min());
  VT_EXPECT_TRUE(Angle::Max() + Angle::Max() == Angle::Max());
  VT_EXPECT_TRUE(Angle::Min() + Angle::Min() == Angle::Min());
  VT_EXPECT_TRUE(Angle::Max() - Angle::Min() == Angle::Max());
  VT_EXPECT_TRUE(Angle::Min() - Angle::Max() == Angle::Min());
  VT_EXPECT_TRUE(-Angle::Min() == Angle::Max());
  VT_EXPECT_TRUE(mjc::Abs(Angle::Min()) == Angle::Max());
  VT_EXPECT_TRUE(Angle::Max() + Angle::Min() == -Angle::Epsilon());
}

// `can_saturate`: whether the edges reach beyond To's range (a product widened into a
// 64-bit format cannot).
template <class To, class A, class B>
void CheckMul(mjc::vt::Context& vt_context, std::uint64_t seed,
              bool can_saturate = true) {
  double worst = 0;
  int saturated = 0;
  ForPairs<A, B>(seed, [&](A a, B b) {
    const double exact = a.ToDouble() * b.ToDouble();
    const To got = mjc::Mul<To>(a, b);
    const double e = ErrorLsb(got, exact) - ReferenceSlackLsb<To>(exact);
    worst = e > worst ? e : worst;
    if (exact > To::Max().ToDouble() || exact < To::Min().ToDouble()) {
      ++saturated;
      VT_EXPECT_TRUE(got == (exact > 0 ? To::Max() : To::Min()));
    }
  });
  VT_EXPECT_LE(worst, 0.5);
  VT_EXPECT_EQ(saturated > 0, can_saturate);
}

MJC_VECTOR_TEST(FixedMul, TorqueTimesVelocityToPower) {
  CheckMul<mjc::Power, mjc::Torque, mjc::AngularVelocity>(vt_context, 21);
}
MJC_VECTOR_TEST(FixedMul, StiffnessTimesAngleToTorque) {
  CheckMul<mjc::Torque, mjc::Stiffness, mjc::Angle>(vt_context, 22);
}
MJC_VECTOR_TEST(FixedMul, CoefficientTimesCoefficient) {
  CheckMul<mjc::Coefficient, mjc::Coefficient, mjc::Coefficient>(vt_context, 23);
}
MJC_VECTOR_TEST(FixedMul, Int16DutyTimesInt16Duty) {
  CheckMul<mjc::Duty, mjc::Duty, mjc::Duty>(vt_context, 24);
}
MJC_VECTOR_TEST(FixedMul, MixedWidthIntoWideFormat) {
  using Wide = Fixed<mjc::Unitless, 40, std::int64_t>;
  CheckMul<Wide, mjc::Ratio, mjc::Duty>(vt_context, 25, /*can_saturate=*/false);
}

MJC_VECTOR_TEST(FixedMul, ProductIsExactBeforeRounding) {
  Rng rng(26);
  for (int i = 0; i < kRandomSamples; ++i) {
    const auto a = mjc::Torque::FromRaw(rng.NextI32());
    const auto b = mjc::AngularVelocity::FromRaw(rng.NextI32());
    const auto p = a * b;
    static_assert(decltype(p)::kFracBits == 44);
    VT_EXPECT_EQ(p.raw(), static_cast<std::int64_t>(a.raw()) * b.raw());
  }
}

template <class To, class From>
void CheckCast(mjc::vt::Context& vt_context, std::uint64_t seed) {
  double worst = 0;
  auto check = [&](From x) {
    const double e = ErrorLsb(mjc::FixedCast<To>(x), x.ToDouble());
    worst = e > worst ? e : worst;
  };
  for (auto r : kEdges<typename From::rep>) check(From::FromRaw(r));
  Rng rng(seed);
  for (int i = 0; i < kRandomSamples; ++i)
    check(From::FromRaw(RandomRaw<typename From::rep>(rng)));
  const bool narrowing = To::kFracBits < From::kFracBits;
  VT_EXPECT_LE(worst, narrowing ? 0.5 : 0.0);
}

MJC_VECTOR_TEST(FixedCast, NarrowingRoundsToNearest) {
  CheckCast<Fixed<mjc::Radian, 12>, mjc::Angle>(vt_context, 31);
}
MJC_VECTOR_TEST(FixedCast, WideningSaturates) {
  CheckCast<Fixed<mjc::Radian, 28>, mjc::Angle>(vt_context, 32);
}
MJC_VECTOR_TEST(FixedCast, Int64ToInt32Saturates) {
  CheckCast<mjc::Power, Fixed<mjc::Watt, 44, std::int64_t>>(vt_context, 33);
}
MJC_VECTOR_TEST(FixedCast, Int32ToInt16) {
  CheckCast<mjc::Duty, Fixed<mjc::Unitless, 20>>(vt_context, 34);
}

MJC_VECTOR_TEST(FixedCast, TiesRoundTowardPlusInfinity) {
  using Coarse = Fixed<mjc::Radian, 0>;
  using Fine = Fixed<mjc::Radian, 1>;
  VT_EXPECT_EQ(mjc::FixedCast<Coarse>(Fine::FromRaw(1)).raw(), 1);    // 0.5 -> 1
  VT_EXPECT_EQ(mjc::FixedCast<Coarse>(Fine::FromRaw(-1)).raw(), 0);   // -0.5 -> 0
  VT_EXPECT_EQ(mjc::FixedCast<Coarse>(Fine::FromRaw(3)).raw(), 2);    // 1.5 -> 2
  VT_EXPECT_EQ(mjc::FixedCast<Coarse>(Fine::FromRaw(-3)).raw(), -1);  // -1.5 -> -1
}

template <class To, class A, class B>
void CheckDivide(mjc::vt::Context& vt_context, std::uint64_t seed) {
  double worst = 0;
  ForPairs<A, B>(seed, [&](A a, B b) {
    const To got = mjc::Divide<To>(a, b);
    if (b.raw() == 0) {
      const To want = a.raw() == 0 ? To{} : (a.raw() > 0 ? To::Max() : To::Min());
      VT_EXPECT_TRUE(got == want);
      return;
    }
    const double exact = a.ToDouble() / b.ToDouble();
    const double e = ErrorLsb(got, exact) - ReferenceSlackLsb<To>(exact);
    worst = e > worst ? e : worst;
  });
  VT_EXPECT_LE(worst, 0.5);
}

MJC_VECTOR_TEST(FixedDivide, AngleOverAngleToRatio) {
  CheckDivide<mjc::Ratio, mjc::Angle, mjc::Angle>(vt_context, 41);
}
MJC_VECTOR_TEST(FixedDivide, TorqueOverAngleToStiffness) {
  CheckDivide<mjc::Stiffness, mjc::Torque, mjc::Angle>(vt_context, 42);
}

MJC_VECTOR_TEST(FixedQuantize, RoundTripWithinHalfLsbAndSaturates) {
  using mjc::Angle;
  Rng rng(51);
  double worst = 0;
  for (int i = 0; i < kRandomSamples; ++i) {
    // Values spanning 2.5x the format's range, so about 60 % saturate.
    const double v = static_cast<double>(rng.NextI32()) * (320.0 / 2147483648.0);
    const double e = ErrorLsb(Angle::Quantize(v), v);
    worst = e > worst ? e : worst;
  }
  VT_EXPECT_LE(worst, 0.5);
  VT_EXPECT_TRUE(Angle::Quantize(1e300) == Angle::Max());
  VT_EXPECT_TRUE(Angle::Quantize(-1e300) == Angle::Min());
  VT_EXPECT_TRUE(Angle::Quantize(std::numeric_limits<double>::quiet_NaN()) == Angle{});
  VT_EXPECT_TRUE(Angle::Quantize(-128.0) == Angle::Min());
}

MJC_VECTOR_TEST(FixedScale, IntegerScalingSaturates) {
  using mjc::Torque;
  Rng rng(61);
  for (int i = 0; i < kRandomSamples; ++i) {
    const auto a = Torque::FromRaw(RandomRaw<std::int32_t>(rng));
    const int n = static_cast<int>(rng.NextI16());
    const double exact = a.ToDouble() * n;
    VT_EXPECT_EQ(ErrorLsb(a * n, exact), 0.0);
  }
  VT_EXPECT_TRUE(Torque::Min() * -1 == Torque::Max());
}

MJC_VECTOR_TEST(FixedLiteral, ConstevalLiteralsMatchRuntimeQuantize) {
  using namespace mjc::literals;
  static_assert((1.0_rad).raw() == (1 << 24));
  static_assert((-0.5_Nm).raw() == -(1 << 23));
  static_assert((180.0_deg).raw() ==
                mjc::Angle::FromDouble(3.14159265358979323846).raw());
  VT_EXPECT_TRUE(0.63_Nm_rad == mjc::Stiffness::Quantize(0.63));
  VT_EXPECT_TRUE(0.0001_s == mjc::Duration::Quantize(0.0001));
  VT_EXPECT_TRUE(25.0_deg == mjc::Angle::Quantize(25.0 * 3.14159265358979323846 / 180.0));
}

MJC_VECTOR_TEST(FixedInteger, WholeConstructorSaturates) {
  VT_EXPECT_EQ(mjc::Angle(3).raw(), 3 << 24);
  VT_EXPECT_TRUE(mjc::Angle(1000) == mjc::Angle::Max());
  VT_EXPECT_TRUE(mjc::Angle(-1000) == mjc::Angle::Min());
  VT_EXPECT_TRUE(mjc::Duty(1) == mjc::Duty::Max());
  VT_EXPECT_TRUE(mjc::Duty(-1) == mjc::Duty::Min());
}

}  // namespace
