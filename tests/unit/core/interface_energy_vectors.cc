// Interface power, energy and motion windows.
//
// The chain test drives the estimator, the torque delay line, the power product and
// the window tracker with a joint moving as θ = A sin ωt against a Kelvin–Voigt
// interface (τ = kθ + bθ̇, hand grounded), sensed through a 14-bit encoder. For that
// motion the energies are analytic: over the loading quarter-period
//   E_load = kA²/2 + bA²ωπ/4,  E_unload = −kA²/2 + bA²ωπ/4,
// so η = 2x/(1 + x) with x = bωπ/(2k); a purely elastic interface (b = 0) gives η = 0.
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>

#include "delay_line.h"
#include "mjc/core/encoder.h"
#include "mjc/core/interface_energy.h"
#include "mjc/core/velocity_estimator.h"
#include "vector_test.h"

namespace {

using namespace mjc;

constexpr std::uint32_t kTickHz = 10000;

MJC_VECTOR_TEST(EnergyScale, SumToJoulesWithinHalfLsb) {
  const EnergyScale scale(kTickHz);
  mjc::vt::Rng rng(121);
  double worst = 0;
  for (int i = 0; i < 20000; ++i) {
    // Up to 2^61: beyond a full day at full-scale power (1.86e18 < 2^61).
    const std::int64_t sum = rng.NextI64() >> (3 + rng.Next() % 40u);
    const double want = static_cast<double>(sum) / (1 << 24) / kTickHz;
    const double got = scale.ToEnergy(sum).ToDouble();
    const double e = std::fabs(got - want) / Energy::Epsilon().ToDouble() -
                     std::fabs(want) * 2.3e-16 / Energy::Epsilon().ToDouble();
    worst = e > worst ? e : worst;
  }
  VT_EXPECT_LE(worst, 0.5);
}

// The window fit's 96-bit sums on both targets (on the Cortex-M4 the int64 part's
// overflows are read from the V flag of an ADCS, on the host from
// __builtin_add_overflow), against a reference kept as two 64-bit sums of the
// products' 32-bit words. Full-scale random products make the int64 part overflow
// both ways many times.
MJC_VECTOR_TEST(Wide96, MatchesWordSumsAcrossOverflows) {
  mjc::vt::Rng rng(961);
  Wide96 w;
  std::uint64_t low_words = 0;  // Σ v mod 2^32
  std::int64_t high_words = 0;  // Σ floor(v / 2^32)
  int mismatches = 0;
  for (int i = 0; i < 20000; ++i) {
    const std::int32_t a = rng.NextI32() >> (rng.Next() % 4u);
    const std::int32_t b = rng.NextI32();
    w.AddProduct(a, b);
    const std::int64_t v = std::int64_t{a} * b;
    low_words += static_cast<std::uint32_t>(static_cast<std::uint64_t>(v));
    high_words += v >> 32;
    const std::int64_t upper = high_words + static_cast<std::int64_t>(low_words >> 32);
    const bool same = w.high() == static_cast<std::int32_t>(upper >> 32) &&
                      w.low() == ((static_cast<std::uint64_t>(upper) << 32) |
                                  (low_words & 0xFFFFFFFFu));
    mismatches += same ? 0 : 1;
  }
  VT_EXPECT_EQ(mismatches, 0);
  // Exact values: 4·2^62 = 2^64, then 8·(−2^31·(2^31 − 1)) = −2^65 + 2^34.
  Wide96 exact;
  for (int i = 0; i < 4; ++i)
    exact.AddProduct(std::numeric_limits<std::int32_t>::min(),
                     std::numeric_limits<std::int32_t>::min());
  VT_EXPECT_EQ(exact.high(), 1);
  VT_EXPECT_EQ(exact.low(), std::uint64_t{0});
  for (int i = 0; i < 8; ++i)
    exact.AddProduct(std::numeric_limits<std::int32_t>::min(),
                     std::numeric_limits<std::int32_t>::max());
  VT_EXPECT_EQ(exact.high(), -1);
  VT_EXPECT_EQ(exact.low(), std::uint64_t{1} << 34);
}

MJC_VECTOR_TEST(EnergyAccumulator, FullScaleDayDoesNotOverflow) {
  // 24 h at 10 kHz of the largest power: 8.64e8 additions of 2^31 − 1 raw.
  EnergyAccumulator acc;
  const std::int64_t ticks = 86400LL * kTickHz;
  for (int i = 0; i < 1000; ++i) acc.Add(Power::Max());
  const std::int64_t per_1000 = acc.raw_sum();
  VT_EXPECT_TRUE(per_1000 <= INT64_MAX / (ticks / 1000));
  const double joules =
      EnergyScale(kTickHz).ToEnergy(per_1000 * (ticks / 1000)).ToDouble();
  VT_EXPECT_NEAR(joules, 128.0 * 86400.0, 128.0 * 86400.0 * 1e-8);
}

MJC_VECTOR_TEST(EtaPercent, MatchesDoubleOverWideRange) {
  mjc::vt::Rng rng(122);
  double worst = 0;
  for (int i = 0; i < 20000; ++i) {
    const std::int64_t load = (rng.NextI64() >> (2 + rng.Next() % 50u));
    const std::int64_t unload = -(rng.NextI64() >> (2 + rng.Next() % 50u));
    bool valid = false;
    const Ratio eta = EtaPercent(load, unload, &valid);
    if (load <= 0) {
      VT_EXPECT_TRUE(!valid);
      continue;
    }
    const double want = (1.0 - std::fabs(double(unload)) / double(load)) * 100.0;
    if (want > 30000 || want < -30000) continue;  // outside Ratio's range
    const double e = std::fabs(eta.ToDouble() - want);
    worst = e > worst ? e : worst;
  }
  VT_EXPECT_LE(worst, 1e-4);  // 0.01 % of a point
}

MJC_VECTOR_TEST(MiddleRepetitions, PaperSelection) {
  const RepetitionRange r = MiddleRepetitions(5, 3);
  VT_EXPECT_EQ(r.first, 1);
  VT_EXPECT_EQ(r.count, 3);
  VT_EXPECT_TRUE(!r.Contains(0) && r.Contains(1) && r.Contains(3) && !r.Contains(4));
  VT_EXPECT_EQ(MiddleRepetitions(2, 3).count, 2);
}

MJC_VECTOR_TEST(WindowTracker, SplitsAndSumsExactly) {
  // A hand-built segment sequence with known powers: each half's energy is the exact
  // sum of its powers, the window ends when unloading ends, an interrupted loading is
  // dropped.
  WindowTracker tracker(kTickHz);
  WindowSummary w;
  InterfaceFitSums sums;
  int completed = 0;
  std::uint32_t tick = 0;
  auto run = [&](Segment s, int n, double watts) {
    for (int i = 0; i < n; ++i, ++tick) {
      if (tracker.Update(tick, s, 7, Power::Quantize(watts), Torque::Quantize(watts * 10),
                         Angle{}, AngularVelocity{}, &w, &sums)) {
        ++completed;
      }
    }
  };
  run(Segment::kRest, 10, 0.0);
  run(Segment::kFlexionLoading, 100, 0.02);
  run(Segment::kFlexionUnloading, 100, -0.01);
  VT_EXPECT_EQ(completed, 0);
  run(Segment::kExtensionLoading, 1, 0.0);
  VT_EXPECT_EQ(completed, 1);
  VT_EXPECT_TRUE(w.motion == Motion::kFlexion);
  VT_EXPECT_EQ(w.repetition, 7);
  VT_EXPECT_EQ(w.start_tick, 10u);
  VT_EXPECT_EQ(w.peak_tick, 110u);
  VT_EXPECT_EQ(w.end_tick, 210u);
  const double p_load = Power::Quantize(0.02).ToDouble(),
               p_unload = Power::Quantize(-0.01).ToDouble();
  VT_EXPECT_NEAR(w.loading.ToDouble(), 100 * p_load / kTickHz, 1e-9);
  VT_EXPECT_NEAR(w.unloading.ToDouble(), 100 * p_unload / kTickHz, 1e-9);
  VT_EXPECT_NEAR(w.net.ToDouble(), 100 * (p_load + p_unload) / kTickHz, 1e-9);
  VT_EXPECT_NEAR(w.positive_work.ToDouble(), 100 * p_load / kTickHz, 1e-9);
  VT_EXPECT_NEAR(w.negative_work.ToDouble(), 100 * p_unload / kTickHz, 1e-9);
  VT_EXPECT_TRUE(w.eta_valid);
  VT_EXPECT_NEAR(w.eta_percent.ToDouble(), 50.0, 1e-3);
  VT_EXPECT_NEAR(w.peak_power.ToDouble(), 0.02, 1e-7);
  VT_EXPECT_NEAR(w.peak_torque.ToDouble(), 0.2, 1e-7);
  // Extension loading interrupted by an idle: dropped, not reported.
  run(Segment::kExtensionLoading, 50, 0.01);
  run(Segment::kIdle, 10, 0.0);
  VT_EXPECT_EQ(completed, 1);
  VT_EXPECT_EQ(tracker.dropped_windows(), 1u);
}

// Runs the power chain on θ = A sin ωt against τ = kθ + bθ̇; returns the mean η of the
// flexion windows of cycles 1..3 and their mean loading energy. `extra_delay` shifts
// the torque by that many more ticks than the estimator's delay (misalignment).
struct ChainResult {
  double eta;
  double loading;
  int windows;
  double stiffness;  // mean fitted k_i of those windows (interface_fit.h), N·m/rad
  double damping;    // mean fitted b_i, N·m·s/rad
};
ChainResult RunChain(double k, double b, int extra_delay) {
  static std::int32_t window_storage[501];
  static std::int32_t torque_storage[400];
  static std::int32_t segment_storage[400];
  VelocityEstimator est(window_storage);
  est.Configure({.window = 501, .tick_hz = kTickHz});
  DelayLine torque_delay(std::span<std::int32_t>(
      torque_storage, static_cast<std::size_t>(est.delay_ticks() + extra_delay)));
  DelayLine segment_delay(std::span<std::int32_t>(segment_storage, est.delay_ticks()));
  torque_delay.Fill(0);
  segment_delay.Fill(static_cast<std::int32_t>(Segment::kRest));
  WindowTracker tracker(kTickHz);
  const JointEncoderConfig enc{.zero_offset = 0, .direction = 1};
  const Stiffness sea = Stiffness::Quantize(0.63);
  const double amp = 25.0 * std::numbers::pi / 180, w = 2 * std::numbers::pi * 0.5;
  const int period = 20000;
  double eta_sum = 0, load_sum = 0, k_sum = 0, b_sum = 0;
  int n = 0;
  est.Reset(Angle{});
  for (int i = 0; i < 5 * period; ++i) {
    const double t = i / double(kTickHz);
    const double theta = amp * std::sin(w * t);
    const double tau = k * theta + b * amp * w * std::cos(w * t);
    // 14-bit joint encoder; the cable side follows from the SEA: τ = K(θ̃ − θ).
    const auto count = static_cast<std::uint16_t>(
        static_cast<std::int32_t>(std::lround(theta / (2 * std::numbers::pi) * 16384)) &
        0x3FFF);
    const Angle joint = DecodeJointFrame(EncodeJointFrame(count, false), enc).angle;
    const Angle cable = Angle::Quantize(theta + tau / sea.ToDouble());
    const Torque torque = Mul<Torque>(sea, cable - joint);
    const int phase = i % period;
    const Segment seg = phase < period / 4       ? Segment::kFlexionLoading
                        : phase < period / 2     ? Segment::kFlexionUnloading
                        : phase < 3 * period / 4 ? Segment::kExtensionLoading
                                                 : Segment::kExtensionUnloading;
    const AngularVelocity v = est.Update(joint);
    const Torque aligned = Torque::FromRaw(torque_delay.Push(torque.raw()));
    const auto seg_aligned =
        static_cast<Segment>(segment_delay.Push(static_cast<std::int32_t>(seg)));
    const Power p = Mul<Power>(aligned, v);
    WindowSummary win;
    InterfaceFitSums sums;
    const auto rep = static_cast<std::uint16_t>((i - est.delay_ticks()) / period);
    if (tracker.Update(static_cast<std::uint32_t>(i), seg_aligned, rep, p, aligned,
                       est.centre(), v, &win, &sums) &&
        win.motion == Motion::kFlexion && win.repetition >= 1 && win.repetition <= 3) {
      eta_sum += win.eta_percent.ToDouble();
      load_sum += win.loading.ToDouble();
      const InterfaceFit fit = SolveInterfaceFit(sums);
      k_sum += fit.valid() ? fit.stiffness.ToDouble() : 0.0;
      b_sum += fit.valid() ? fit.damping.ToDouble() : 0.0;
      ++n;
    }
  }
  return {n ? eta_sum / n : 0.0, n ? load_sum / n : 0.0, n, n ? k_sum / n : 0.0,
          n ? b_sum / n : 0.0};
}

MJC_VECTOR_TEST(PowerChain, ElasticInterfaceReadsNoLoss) {
  const ChainResult r = RunChain(3.1, 0.0, 0);
  VT_EXPECT_EQ(r.windows, 3);
  VT_EXPECT_LE(std::fabs(r.eta), 0.5);  // points
  const double amp = 25.0 * std::numbers::pi / 180;
  VT_EXPECT_NEAR(r.loading, 3.1 * amp * amp / 2, 0.01 * 3.1 * amp * amp / 2);
}

MJC_VECTOR_TEST(PowerChain, WindowFitFindsTheInterface) {
  // The same chain's window sums, solved as the main loop does: the analytic k and b
  // the torque was made from, through a 14-bit encoder and the velocity estimator
  // (whose amplitude loss is 0.06 %, SIGNAL_CHAIN.md).
  const ChainResult elastic = RunChain(3.1, 0.0, 0);
  VT_EXPECT_NEAR(elastic.stiffness, 3.1, 3.1 * 0.005);
  VT_EXPECT_NEAR(elastic.damping, 0.0, 0.005);
  const ChainResult lossy = RunChain(3.1, 0.2, 0);
  VT_EXPECT_EQ(lossy.windows, 3);
  VT_EXPECT_NEAR(lossy.stiffness, 3.1, 3.1 * 0.005);
  VT_EXPECT_NEAR(lossy.damping, 0.2, 0.2 * 0.01);
}

MJC_VECTOR_TEST(PowerChain, MisalignedTorqueWouldReadFalseLoss) {
  // The same elastic interface with τ delayed 5 ms more than θ̇: false loss of
  // several points (SIGNAL_CHAIN.md: ~5 points at 0.5 Hz), so alignment is what keeps
  // the elastic case at zero.
  const ChainResult r = RunChain(3.1, 0.0, 50);
  VT_EXPECT_TRUE(std::fabs(r.eta) > 3.0);
}

MJC_VECTOR_TEST(PowerChain, KelvinVoigtMatchesAnalyticEta) {
  const double k = 3.1, b = 0.18, w = std::numbers::pi;
  const double x = b * w * std::numbers::pi / (2 * k);
  const double want_eta = 200 * x / (1 + x);
  const double amp = 25.0 * std::numbers::pi / 180;
  const double want_load = k * amp * amp / 2 + b * amp * amp * w * std::numbers::pi / 4;
  const ChainResult r = RunChain(k, b, 0);
  VT_EXPECT_EQ(r.windows, 3);
  VT_EXPECT_NEAR(r.eta, want_eta, 0.5);
  VT_EXPECT_NEAR(r.loading, want_load, 0.01 * want_load);
}

}  // namespace
