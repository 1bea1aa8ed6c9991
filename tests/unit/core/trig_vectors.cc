// Sin and Cos (mjc/core/trig.h) against std::sin / std::cos in double, and their exact
// symmetries. These vectors run on the host and on the Cortex-M4 under QEMU.
//
// Error bound, in LSB of Q1.30 (2^-30 = 9.3e-10): |Sin - sin|, |Cos - cos| <= 1 LSB
// (trig.h: 0.834 LSB measured over every quarter-wave input). The double reference is
// good to ~1e-15, i.e. 1e-6 LSB, so it does not eat into the bound.
#include <cmath>
#include <cstdint>
#include <numbers>

#include "mjc/core/quantities.h"
#include "mjc/core/trig.h"
#include "vector_test.h"

namespace {

using mjc::Coefficient;
using mjc::vt::Rng;

constexpr double kMaxErrorLsb = 1.0;
constexpr int kRandomPhases = 100000;
constexpr double kTwoPi = 2.0 * std::numbers::pi;
constexpr std::uint32_t kQuarter = std::uint32_t{1} << 30;
constexpr std::uint32_t kHalf = std::uint32_t{1} << 31;

double Radians(std::uint32_t phase) {
  return kTwoPi * (static_cast<double>(phase) / 4294967296.0);
}

double ErrorLsb(Coefficient got, double exact) {
  return std::fabs(got.ToDouble() - exact) * 1073741824.0;
}

// Calls f(phase) on every phase within ±kSpan of the four quadrant boundaries (where the
// quarter-wave reduction switches direction and sign), on the first and last phases of
// the turn, and on kRandomPhases uniform random phases.
template <class F>
void ForPhases(std::uint64_t seed, F f) {
  constexpr std::int32_t kSpan = 600;
  for (std::uint32_t q = 0; q < 4; ++q) {
    for (std::int32_t d = -kSpan; d <= kSpan; ++d) {
      f(static_cast<std::uint32_t>(q * kQuarter + static_cast<std::uint32_t>(d)));
    }
  }
  Rng rng(seed);
  for (int i = 0; i < kRandomPhases; ++i) f(static_cast<std::uint32_t>(rng.Next() >> 32));
}

MJC_VECTOR_TEST(TrigSin, WithinOneLsbOfStdSin) {
  double worst = 0;
  int count = 0;
  ForPhases(101, [&](std::uint32_t phase) {
    const double e = ErrorLsb(mjc::Sin(phase), std::sin(Radians(phase)));
    worst = e > worst ? e : worst;
    ++count;
  });
  VT_EXPECT_LE(worst, kMaxErrorLsb);
  VT_EXPECT_TRUE(count > 100000);
}

MJC_VECTOR_TEST(TrigCos, WithinOneLsbOfStdCos) {
  double worst = 0;
  ForPhases(102, [&](std::uint32_t phase) {
    const double e = ErrorLsb(mjc::Cos(phase), std::cos(Radians(phase)));
    worst = e > worst ? e : worst;
  });
  VT_EXPECT_LE(worst, kMaxErrorLsb);
}

// Near the peak the slope vanishes, so the final rounding and the Q33 partial matter
// most there (the measured worst case sits at 98 % of a quarter wave): every phase of
// a dense stretch below the peak.
MJC_VECTOR_TEST(TrigSin, DenseBelowPeak) {
  double worst = 0;
  const std::uint32_t first = kQuarter - kQuarter / 50;
  for (std::uint32_t phase = first; phase <= kQuarter; phase += 997) {
    const double e = ErrorLsb(mjc::Sin(phase), std::sin(Radians(phase)));
    worst = e > worst ? e : worst;
  }
  VT_EXPECT_LE(worst, kMaxErrorLsb);
}

MJC_VECTOR_TEST(TrigSin, ExactAtQuadrantBoundaries) {
  static_assert(mjc::Sin(0).raw() == 0);
  static_assert(mjc::Sin(kQuarter).raw() == (1 << 30));
  static_assert(mjc::Cos(0).raw() == (1 << 30));
  VT_EXPECT_EQ(mjc::Sin(0).raw(), 0);
  VT_EXPECT_EQ(mjc::Sin(kQuarter).raw(), 1 << 30);
  VT_EXPECT_EQ(mjc::Sin(kHalf).raw(), 0);
  VT_EXPECT_EQ(mjc::Sin(3u * kQuarter).raw(), -(1 << 30));
  VT_EXPECT_EQ(mjc::Cos(0).raw(), 1 << 30);
  VT_EXPECT_EQ(mjc::Cos(kQuarter).raw(), 0);
  VT_EXPECT_EQ(mjc::Cos(kHalf).raw(), -(1 << 30));
  VT_EXPECT_EQ(mjc::Cos(3u * kQuarter).raw(), 0);
  // The smallest phase step: sin(2π/2^32) = 1.46e-9 = 1.57 LSB, rounds to 2.
  VT_EXPECT_EQ(mjc::Sin(1).raw(), 2);
  VT_EXPECT_EQ(mjc::Sin(0xFFFFFFFFu).raw(), -2);
}

MJC_VECTOR_TEST(TrigSin, NeverExceedsOne) {
  Rng rng(103);
  bool within = true;
  for (std::int32_t d = -2000; d <= 2000; ++d) {
    const auto near_peak =
        static_cast<std::uint32_t>(kQuarter + static_cast<std::uint32_t>(d));
    const auto near_trough =
        static_cast<std::uint32_t>(3u * kQuarter + static_cast<std::uint32_t>(d));
    within = within && mjc::Sin(near_peak).raw() <= (1 << 30);
    within = within && mjc::Sin(near_trough).raw() >= -(1 << 30);
  }
  for (int i = 0; i < 20000; ++i) {
    const auto phase = static_cast<std::uint32_t>(rng.Next() >> 32);
    const std::int32_t s = mjc::Sin(phase).raw();
    within = within && s <= (1 << 30) && s >= -(1 << 30);
  }
  VT_EXPECT_TRUE(within);
}

// Odd / even symmetry, half-turn antisymmetry and the quarter-turn shift hold bit for
// bit, which is what lets a trajectory's flexion and extension lobes mirror exactly.
MJC_VECTOR_TEST(TrigSin, SymmetriesAreExact) {
  Rng rng(104);
  int broken = 0;
  for (int i = 0; i < 20000; ++i) {
    const auto p = static_cast<std::uint32_t>(rng.Next() >> 32);
    const auto minus_p = static_cast<std::uint32_t>(0u - p);
    const std::int32_t s = mjc::Sin(p).raw();
    if (mjc::Sin(minus_p).raw() != -s) ++broken;                                // odd
    if (mjc::Sin(static_cast<std::uint32_t>(p + kHalf)).raw() != -s) ++broken;  // π shift
    if (mjc::Sin(static_cast<std::uint32_t>(kHalf - p)).raw() != s) ++broken;   // π - x
    if (mjc::Cos(minus_p).raw() != mjc::Cos(p).raw()) ++broken;                 // even
    if (mjc::Cos(p).raw() != mjc::Sin(static_cast<std::uint32_t>(p + kQuarter)).raw()) {
      ++broken;
    }
  }
  VT_EXPECT_EQ(broken, 0);
}

// SinCos (the trajectory's per-tick pair) is Sin and Cos bit for bit: around every
// quadrant boundary, where it switches which quarter-wave value is which, and at random.
MJC_VECTOR_TEST(TrigSinCos, EqualsSinAndCosBitForBit) {
  Rng rng(106);
  int broken = 0;
  const auto check = [&broken](std::uint32_t p) {
    const mjc::SineCosine sc = mjc::SinCos(p);
    if (sc.sine.raw() != mjc::Sin(p).raw()) ++broken;
    if (sc.cosine.raw() != mjc::Cos(p).raw()) ++broken;
  };
  for (std::uint32_t q = 0; q < 4; ++q) {
    for (std::int32_t d = -3; d <= 3; ++d) {
      check(static_cast<std::uint32_t>(q * kQuarter + static_cast<std::uint32_t>(d)));
    }
  }
  for (int i = 0; i < 20000; ++i) check(static_cast<std::uint32_t>(rng.Next() >> 32));
  VT_EXPECT_EQ(broken, 0);
}

// sin² + cos² = 1 within the two roundings: |Δ| <= 2·(1 LSB)·1 + (1 LSB)² ≈ 2 LSB.
MJC_VECTOR_TEST(TrigSin, PythagoreanIdentity) {
  Rng rng(105);
  double worst = 0;
  for (int i = 0; i < 20000; ++i) {
    const auto p = static_cast<std::uint32_t>(rng.Next() >> 32);
    const double s = mjc::Sin(p).ToDouble();
    const double c = mjc::Cos(p).ToDouble();
    const double e = std::fabs(s * s + c * c - 1.0) * 1073741824.0;
    worst = e > worst ? e : worst;
  }
  VT_EXPECT_LE(worst, 2.0);
}

}  // namespace
