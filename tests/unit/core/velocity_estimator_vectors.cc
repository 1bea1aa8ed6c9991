// The sliding least-squares velocity estimator against a direct double-precision
// least-squares fit recomputed from scratch over the window, and against the analytic
// derivative of a sinusoid at the window's centre (the estimator's exact group delay).
#include <cmath>
#include <cstdint>
#include <numbers>

#include "delay_line.h"
#include "mjc/core/velocity_estimator.h"
#include "vector_test.h"

namespace {

using mjc::Angle;
using mjc::AngularVelocity;
using mjc::VelocityEstimator;
using mjc::VelocityEstimatorConfig;
using mjc::VelocityEstimatorError;

constexpr double kVelocityLsb = 1.0 / (1 << 20);

std::int32_t g_storage[2001];

// Least-squares slope (rad/s) of the last n samples of x ending at index `end`.
double ReferenceSlope(const std::int32_t* x, int end, int n, double tick_hz) {
  const double c = (n - 1) / 2.0;
  double num = 0, den = 0;
  for (int i = 0; i < n; ++i) {
    const double xi = x[end - n + 1 + i] / double(1 << 24);
    num += (i - c) * xi;
    den += (i - c) * (i - c);
  }
  return num / den * tick_hz;
}

MJC_VECTOR_TEST(VelocityEstimator, MatchesDirectLeastSquaresOnRandomSignal) {
  static std::int32_t x[12000];
  mjc::vt::Rng rng(111);
  std::int32_t pos = 0;
  for (auto& v : x) {
    pos += rng.NextI32() >> 20;  // a random walk with ±2048-LSB steps
    v = pos;
  }
  VelocityEstimator est(g_storage);
  VT_EXPECT_TRUE(est.Configure({.window = 501, .tick_hz = 10000}) ==
                 VelocityEstimatorError::kOk);
  est.Reset(Angle::FromRaw(x[0]));
  double worst = 0;
  for (int i = 1; i < 12000; ++i) {
    const AngularVelocity v = est.Update(Angle::FromRaw(x[i]));
    if (i >= 501 && i % 97 == 0) {
      const double e =
          std::fabs(v.ToDouble() - ReferenceSlope(x, i, 501, 10000)) / kVelocityLsb;
      worst = e > worst ? e : worst;
    }
  }
  // One rounding of the scaled sum (0.5 LSB) plus the multiplier's 2^-29 precision.
  VT_EXPECT_LE(worst, 0.6);
}

MJC_VECTOR_TEST(VelocityEstimator, AddsTheCentreStepToTheSlope) {
  // Samples of a residual and a known per-tick step at the window's centre (the
  // attachment model's, in ModelAngle raw): the slope plus step·f_tick.
  static std::int32_t x[6000], step[6000];
  mjc::vt::Rng rng(112);
  std::int32_t pos = 0;
  for (int i = 0; i < 6000; ++i) {
    pos += rng.NextI32() >> 20;
    x[i] = pos;
    step[i] = rng.NextI32() >> 15;  // up to ±65,536 LSB: ±4.9 rad/s
  }
  constexpr int kN = 1001;
  VelocityEstimator est(g_storage);
  VT_EXPECT_TRUE(est.Configure({.window = kN, .tick_hz = 10000}) ==
                 VelocityEstimatorError::kOk);
  est.Reset(Angle::FromRaw(x[0]));
  const int c = est.delay_ticks();
  double worst = 0;
  for (int i = 1; i < 6000; ++i) {
    const std::int32_t centre_step = i >= c ? step[i - c] : 0;
    const AngularVelocity v = est.Update(Angle::FromRaw(x[i]), centre_step);
    if (i >= kN && i % 53 == 0) {
      const double want =
          ReferenceSlope(x, i, kN, 10000) + centre_step / double(1 << 27) * 10000;
      worst = std::fmax(worst, std::fabs(v.ToDouble() - want) / kVelocityLsb);
    }
  }
  VT_EXPECT_LE(worst, 0.6);
}

MJC_VECTOR_TEST(VelocityEstimator, RampIsExactAfterWindowFills) {
  VelocityEstimator est(g_storage);
  est.Configure({.window = 201, .tick_hz = 10000});
  est.Reset(Angle{});
  // 0.2 rad/s = 2e-5 rad per tick = 335.54432 LSB per tick: use an exact 336 LSB/tick.
  AngularVelocity v;
  for (int i = 1; i <= 1000; ++i) v = est.Update(Angle::FromRaw(336 * i));
  const double want = 336.0 / (1 << 24) * 10000;
  VT_EXPECT_NEAR(v.ToDouble(), want, 0.5 * kVelocityLsb);
}

MJC_VECTOR_TEST(VelocityEstimator, GroupDelayIsHalfTheWindow) {
  // On a 0.5 Hz sinusoid the estimate at tick n is the derivative at n − (N−1)/2,
  // scaled by the least-squares gain 3(sin x − x cos x)/x³, x = π f N dt; there is no
  // phase error. A wrong delay of even 1 ms would show as an error of 2π·0.5·1e-3 of
  // the peak (0.3 %); the bound here is 0.01 % of the peak velocity.
  const int n = 601;
  VelocityEstimator est(g_storage);
  est.Configure({.window = static_cast<std::uint16_t>(n), .tick_hz = 10000});
  VT_EXPECT_EQ(est.delay_ticks(), 300);
  const double amp = 0.3, w = 2 * std::numbers::pi * 0.5;
  const double x = std::numbers::pi * 0.5 * n * 1e-4;
  const double gain = 3 * (std::sin(x) - x * std::cos(x)) / (x * x * x);
  est.Reset(Angle::Quantize(0.0));
  double worst = 0;
  for (int i = 1; i < 40000; ++i) {
    const AngularVelocity v = est.Update(Angle::Quantize(amp * std::sin(w * i * 1e-4)));
    if (i >= n) {
      const double want = gain * amp * w * std::cos(w * (i - (n - 1) / 2) * 1e-4);
      const double e = std::fabs(v.ToDouble() - want);
      worst = e > worst ? e : worst;
    }
  }
  VT_EXPECT_LE(worst, 1e-4 * amp * w);
}

MJC_VECTOR_TEST(VelocityEstimator, RunningSumsDoNotDrift) {
  // Two million ticks of a random walk, then a constant: the estimate returns to zero
  // exactly, as the sums hold exactly the window's samples.
  VelocityEstimator est(g_storage);
  est.Configure({.window = 501, .tick_hz = 10000});
  est.Reset(Angle{});
  mjc::vt::Rng rng(112);
  std::int32_t pos = 0;
  for (int i = 0; i < 2000000; ++i) {
    pos += rng.NextI32() >> 18;
    pos = pos > (1 << 28) ? (1 << 28) : (pos < -(1 << 28) ? -(1 << 28) : pos);
    est.Update(Angle::FromRaw(pos));
  }
  AngularVelocity v;
  for (int i = 0; i < 501; ++i) v = est.Update(Angle::FromRaw(pos));
  VT_EXPECT_EQ(v.raw(), 0);
}

MJC_VECTOR_TEST(VelocityEstimator, ConfigureRefusesAndKeepsOldConfig) {
  VelocityEstimator est(g_storage);
  VT_EXPECT_TRUE(est.Configure({.window = 501, .tick_hz = 10000}) ==
                 VelocityEstimatorError::kOk);
  VT_EXPECT_TRUE(est.Configure({.window = 500, .tick_hz = 10000}) ==
                 VelocityEstimatorError::kWindowEven);
  VT_EXPECT_TRUE(est.Configure({.window = 31, .tick_hz = 10000}) ==
                 VelocityEstimatorError::kWindowTooShort);
  VT_EXPECT_TRUE(est.Configure({.window = 2003, .tick_hz = 10000}) ==
                 VelocityEstimatorError::kWindowTooLong);
  VT_EXPECT_TRUE(est.Configure({.window = 501, .tick_hz = 50}) ==
                 VelocityEstimatorError::kTickRateOutOfRange);
  VT_EXPECT_TRUE(est.Configure({.window = 33, .tick_hz = 100000}) ==
                 VelocityEstimatorError::kWindowTooShort);  // scale does not fit
  VT_EXPECT_EQ(est.window(), 501);
}

MJC_VECTOR_TEST(DelayLine, ReturnsWhatWasPushedDelayTicksAgo) {
  std::int32_t slots[7];
  mjc::DelayLine line(slots);
  line.Fill(-5);
  for (int i = 0; i < 7; ++i) VT_EXPECT_EQ(line.Push(i), -5);
  for (int i = 7; i < 100; ++i) VT_EXPECT_EQ(line.Push(i), i - 7);
}

}  // namespace
