// The interface fit against independent references (host only): the 96-bit sums
// against __int128, the fixed-point solve against a double-precision least squares
// (Eigen's QR on the same samples' values).
#include "mjc/core/interface_fit.h"

#include <gtest/gtest.h>

// GCC's -Wnull-dereference misreads Eigen's dynamic-size QR once inlined here (a false
// positive inside Eigen's own functors); silenced for this reference only.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wnull-dereference"
#include <Eigen/Dense>
#pragma GCC diagnostic pop
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <vector>

#include "vector_test.h"

namespace {

using namespace mjc;

__int128 Value(const Wide96& w) {
  return (static_cast<__int128>(w.high()) << 64) | static_cast<__int128>(w.low());
}

TEST(Wide96, SumsAndDividesLikeInt128) {
  mjc::vt::Rng rng(301);
  for (int trial = 0; trial < 200; ++trial) {
    Wide96 w;
    __int128 want = 0;
    const int terms = 1 + static_cast<int>(rng.Next() % 5000u);
    // Products of two int32, the extremes included: the tick's terms.
    for (int i = 0; i < terms; ++i) {
      const std::int64_t a = i % 97 == 0 ? std::numeric_limits<std::int32_t>::min()
                                         : std::int64_t{rng.NextI32()};
      const std::int64_t b = i % 89 == 0 ? std::numeric_limits<std::int32_t>::min()
                                         : std::int64_t{rng.NextI32()};
      w.AddProduct(static_cast<std::int32_t>(a), static_cast<std::int32_t>(b));
      want += static_cast<__int128>(a * b);
    }
    ASSERT_TRUE(Value(w) == want);
    const auto n = static_cast<std::uint32_t>(terms);
    const __int128 q = want / n, r = want % n;
    const __int128 twice = 2 * (r < 0 ? -r : r);
    const __int128 rounded = twice >= n ? (want < 0 ? q - 1 : q + 1) : q;
    EXPECT_EQ(w.RoundDivide(n), static_cast<std::int64_t>(rounded));
  }
}

TEST(Wide96, LongestWindowOfFullScaleProductsFits) {
  // The bound of interface_fit.h: 2^32 − 1 terms of 2^62 stay below 2^95. Adding 2^62
  // 2^32 − 1 times is 4e9 additions; the sum is linear, so check the carries on a
  // shortened run and the arithmetic of the bound; and a run of the largest negative
  // and positive products, whose low words carry on every addition.
  Wide96 w;
  const std::int64_t full = std::int64_t{1} << 62;
  const std::int32_t min = std::numeric_limits<std::int32_t>::min();
  for (int i = 0; i < 1 << 20; ++i) w.AddProduct(min, min);
  EXPECT_TRUE(Value(w) == (static_cast<__int128>(full) << 20));
  Wide96 mixed;
  __int128 want = 0;
  const std::int32_t max = std::numeric_limits<std::int32_t>::max();
  for (int i = 0; i < 1 << 20; ++i) {
    mixed.AddProduct(i % 3 ? max : min, max);
    want += static_cast<__int128>(std::int64_t{i % 3 ? max : min} * max);
  }
  EXPECT_TRUE(Value(mixed) == want);
  const __int128 longest = static_cast<__int128>(full) * 0xFFFFFFFFu;
  EXPECT_TRUE(longest < (static_cast<__int128>(1) << 95));
}

struct Samples {
  std::vector<Angle> theta;
  std::vector<AngularVelocity> omega;
  std::vector<Torque> tau;
};

// θ = offset + A sin ωt over half a cycle; τ = kθ + bθ̇ + τ_0 plus Gaussian noise.
Samples Make(double amplitude, double offset, double k, double b, double tau0,
             double noise_Nm, std::uint64_t seed) {
  mjc::vt::Rng rng(seed);
  const auto gauss = [&rng] {
    const double u1 = (static_cast<double>(rng.Next() >> 11) + 0.5) * 0x1p-53;
    const double u2 = static_cast<double>(rng.Next() >> 11) * 0x1p-53;
    return std::sqrt(-2 * std::log(u1)) * std::cos(2 * std::numbers::pi * u2);
  };
  Samples s;
  const double w = 2 * std::numbers::pi * 0.5;
  for (int i = 0; i < 10000; ++i) {
    const double t = i / 10000.0;
    const double theta = offset + amplitude * std::sin(w * t);
    const double omega = amplitude * w * std::cos(w * t) + 1e-3 * gauss();
    s.theta.push_back(Angle::Quantize(theta));
    s.omega.push_back(AngularVelocity::Quantize(omega));
    s.tau.push_back(Torque::Quantize(k * theta + b * omega + tau0 + noise_Nm * gauss()));
  }
  return s;
}

struct Reference {
  double k, b, tau0, rms;
  double tau_sd;  // standard deviation of τ over the samples
  double theta_mean, omega_mean;
};

// Least squares in double on the quantised samples' values: Eigen's Householder QR
// of the n×3 regressor matrix (no normal equations, no fixed point).
Reference Solve(const Samples& s) {
  const auto n = static_cast<Eigen::Index>(s.theta.size());
  Eigen::Matrix<double, Eigen::Dynamic, 3> x(n, 3);
  Eigen::VectorXd y(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const auto j = static_cast<std::size_t>(i);
    x(i, 0) = s.theta[j].ToDouble();
    x(i, 1) = s.omega[j].ToDouble();
    x(i, 2) = 1.0;
    y(i) = s.tau[j].ToDouble();
  }
  const Eigen::Vector3d p = x.householderQr().solve(y);
  const double rms = std::sqrt((x * p - y).squaredNorm() / static_cast<double>(n));
  const double sd = std::sqrt((y.array() - y.mean()).square().mean());
  return {p(0), p(1), p(2), rms, sd, x.col(0).mean(), x.col(1).mean()};
}

InterfaceFit Fit(const Samples& s) {
  InterfaceFitSums sums;
  for (std::size_t i = 0; i < s.theta.size(); ++i)
    sums.Add(s.theta[i], s.omega[i], s.tau[i]);
  return SolveInterfaceFit(sums);
}

// The fixed-point solve's own error budget (interface_fit.h): the centred moments are
// within 2 raw² units (≤ 1e-9 relative for these motions, ≥ 2° about up to 0.5 rad);
// k_i and b_i are rounded to Q24 (6e-8); τ_0 adds the rounding of the means and of
// k_i·θ̄, b_i·ω̄ (a few LSB); the residual variance goes through a Q26 solution
// (≤ 6e-8 of the torque's variance). Tolerances: 1e-7 relative + 2 LSB on k_i and
// b_i, on τ_0 what those allow through the means (|θ̄|·δk + |ω̄|·δb) + 2 LSB, and on the
// residual variance 1e-6 relative + 1e-7 of the torque's variance.
TEST(InterfaceFit, AgreesWithDoubleLeastSquares) {
  const double lsb = 0x1p-24;
  struct Case {
    double amplitude_deg, offset, k, b, tau0, noise;
  };
  const Case cases[] = {
      {25, 0.3, 4.5, 0.25, 0.012, 0.0},   {25, 0.3, 4.5, 0.25, 0.012, 0.002},
      {11, -0.2, 5.5, 0.29, 0.02, 0.004}, {2, 0.3, 4.0, 0.235, 0.006, 0.001},
      {40, 0.0, 3.0, 0.0, 0.0, 0.001},    {25, 0.5, 60.0, 3.0, -0.5, 0.05},
  };
  std::uint64_t seed = 310;
  for (const Case& c : cases) {
    const Samples s = Make(c.amplitude_deg * std::numbers::pi / 180, c.offset, c.k, c.b,
                           c.tau0, c.noise, ++seed);
    const Reference want = Solve(s);
    const InterfaceFit got = Fit(s);
    SCOPED_TRACE(c.amplitude_deg);
    ASSERT_TRUE(got.valid());
    const double dk = 1e-7 * std::fabs(want.k) + 2 * lsb;
    const double db = 1e-7 * std::fabs(want.b) + 2 * lsb;
    EXPECT_NEAR(got.stiffness.ToDouble(), want.k, dk);
    EXPECT_NEAR(got.damping.ToDouble(), want.b, db);
    EXPECT_NEAR(
        got.offset.ToDouble(), want.tau0,
        std::fabs(want.theta_mean) * dk + std::fabs(want.omega_mean) * db + 2 * lsb);
    const double rms = got.residual_rms.ToDouble();
    const double variance = want.tau_sd * want.tau_sd;
    EXPECT_NEAR(rms * rms, want.rms * want.rms,
                1e-6 * want.rms * want.rms + 1e-7 * variance + 2 * lsb * rms);
  }
}

TEST(InterfaceFit, RefusesWhatCannotBeFitted) {
  InterfaceFitSums few;
  for (int i = 0; i < 999; ++i)
    few.Add(Angle::Quantize(i * 1e-4), AngularVelocity{}, Torque{});
  EXPECT_EQ(SolveInterfaceFit(few).status, InterfaceFitStatus::kTooFewSamples);

  InterfaceFitSums still;
  for (int i = 0; i < 5000; ++i) {
    still.Add(Angle::Quantize(0.1), AngularVelocity::Quantize(0.0),
              Torque::Quantize(0.3));
  }
  EXPECT_EQ(SolveInterfaceFit(still).status, InterfaceFitStatus::kNoMotion);

  // θ̇ proportional to θ: k_i and b_i cannot be told apart.
  InterfaceFitSums collinear;
  for (int i = 0; i < 5000; ++i) {
    const double theta = std::sin(i * 1e-3);
    collinear.Add(Angle::Quantize(theta), AngularVelocity::Quantize(2 * theta),
                  Torque::Quantize(theta));
  }
  EXPECT_EQ(SolveInterfaceFit(collinear).status, InterfaceFitStatus::kCollinear);
  EXPECT_EQ(SolveInterfaceFit(collinear).stiffness.raw(), 0);
}

}  // namespace
