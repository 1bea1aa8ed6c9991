#include "mjc/core/interface_fit.h"

#include <Eigen/Core>

namespace mjc {
namespace {

using Matrix2 = Eigen::Matrix<std::int64_t, 2, 2>;
using Vector2 = Eigen::Matrix<std::int64_t, 2, 1>;

using fixed_detail::BitLength;

std::uint64_t Magnitude(std::int64_t v) {
  return v < 0 ? 0 - static_cast<std::uint64_t>(v) : static_cast<std::uint64_t>(v);
}

// round(a / b), b > 0, ties away from zero.
std::int64_t RoundDivide(std::int64_t a, std::int64_t b) {
  const std::int64_t q = a / b, r = a % b;
  const std::uint64_t twice = 2 * Magnitude(r);
  if (twice >= static_cast<std::uint64_t>(b)) return a < 0 ? q - 1 : q + 1;
  return q;
}

// v·2^-s rounded to nearest (s > 0), or v·2^-s exactly (s ≤ 0; the caller keeps it in
// range).
std::int64_t Shift(std::int64_t v, int s) {
  if (s <= 0) return static_cast<std::int64_t>(static_cast<std::uint64_t>(v) << -s);
  if (s >= 63) return 0;
  const std::int64_t half = std::int64_t{1} << (s - 1);
  return v > INT64_MAX - half ? v >> s : (v + half) >> s;
}

// round(num·2^e / den) for den > 0, |num| < 2^62, |den| < 2^62: the operands are
// shifted so that neither overflows, keeping at least 30 significant bits of the
// divisor. Saturates at ±2^62.
std::int64_t ScaledQuotient(std::int64_t num, std::int64_t den, int e) {
  if (num == 0) return 0;
  if (e >= 0) {
    const int room = 61 - BitLength(Magnitude(num));
    const int up = e < room ? e : room;
    num = Shift(num, -up);
    den = Shift(den, e - up);
  } else {
    const int room = 61 - BitLength(Magnitude(den));
    const int up = -e < room ? -e : room;
    den = Shift(den, -up);
    num = Shift(num, -e - up);
  }
  if (den <= 0) return num < 0 ? -(std::int64_t{1} << 62) : std::int64_t{1} << 62;
  return RoundDivide(num, den);
}

// Integer square root: floor(√v), v ≥ 0 (bit by bit; the C library offers only the
// floating-point one).
std::uint64_t SquareRoot(std::uint64_t v) {
  std::uint64_t root = 0;
  std::uint64_t bit = std::uint64_t{1} << 62;
  while (bit > v) bit >>= 2;
  while (bit != 0) {
    if (v >= root + bit) {
      v -= root + bit;
      root = (root >> 1) + bit;
    } else {
      root >>= 1;
    }
    bit >>= 2;
  }
  return root;
}

// The shift s that brings a variance c (> 0) to 29–30 bits as c·2^-2s.
int VarianceShift(std::int64_t c) {
  const int excess = BitLength(static_cast<std::uint64_t>(c)) - 30;
  return excess >= 0 ? (excess + 1) / 2 : -((-excess) / 2);
}

bool FitsInt32(std::int64_t v) { return v >= INT32_MIN && v <= INT32_MAX; }

// a − b for |a|, |b| ≤ 2^62 (the difference of two int64 moments), saturating.
std::int64_t Difference(std::int64_t a, std::int64_t b) {
  std::int64_t d = 0;
  if (__builtin_sub_overflow(a, b, &d)) return a < 0 ? INT64_MIN : INT64_MAX;
  return d;
}

// A sum's mean as S = q·n + r (q = S / n truncated, |r| < n).
struct Mean {
  std::int64_t q = 0;
  std::int64_t r = 0;
};
Mean MeanOf(std::int64_t sum, std::uint32_t n) {
  const auto count = static_cast<std::int64_t>(n);
  return {sum / count, sum % count};
}

// The centred moment (S_xy − S_x·S_y/n)/n of one window, raw units squared. With
// S_x = q_x·n + r_x it is S_xy/n − q_x·q_y − (q_x·r_y + q_y·r_x)/n − r_x·r_y/n²: each
// term fits int64 (|q| < 2^31, |r| < 2^32) and the last is below 1, so dropped. Error
// ≤ 2 raw² units (three roundings and the dropped term), whatever the means: rounding
// the means instead would cost |mean| units (1e-4 relative for a 2° motion about
// 0.3 rad).
std::int64_t Centred(const Wide96& sum, Mean x, Mean y, std::uint32_t n) {
  const auto count = static_cast<std::int64_t>(n);
  const std::int64_t cross =
      RoundDivide(x.q * y.r, count) + RoundDivide(y.q * x.r, count);
  return Difference(Difference(sum.RoundDivide(n), x.q * y.q), cross);
}

// x·(q + r/n) for a Q-format x and a mean q + r/n, in the product's format: |x·q| <
// 2^62 and |x·r| < 2^63 since |x| ≤ 2^31, |q| < 2^31, |r| < n ≤ 2^32.
std::int64_t Times(std::int32_t x, Mean m, std::uint32_t n) {
  return x * m.q + RoundDivide(x * m.r, static_cast<std::int64_t>(n));
}

// τ_0 = τ̄ − k·θ̄ − b·ω̄ (raw Q24) from the exact means, summed in Q44 (τ̄·2^20, k·θ̄ is
// Q48, b·ω̄ Q44) and rounded once: within 1 LSB of the value for the rounded k_i, b_i.
std::int64_t Offset(Mean tau, Mean theta, Mean omega, std::int32_t k, std::int32_t b,
                    std::uint32_t n) {
  const std::int64_t tau_q44 =
      tau.q * (std::int64_t{1} << 20) +
      RoundDivide(tau.r * (std::int64_t{1} << 20), static_cast<std::int64_t>(n));
  const std::int64_t sum =
      Difference(Difference(tau_q44, Shift(Times(k, theta, n), 4)), Times(b, omega, n));
  return Shift(sum, 20);
}

}  // namespace

void InterfaceFitSums::Add(Angle theta_j, AngularVelocity omega_j, Torque torque) {
  const std::int32_t t = theta_j.raw(), w = omega_j.raw(), q = torque.raw();
  ++count;
  theta += t;
  omega += w;
  tau += q;
  theta_theta.AddProduct(t, t);
  theta_omega.AddProduct(t, w);
  omega_omega.AddProduct(w, w);
  theta_tau.AddProduct(t, q);
  omega_tau.AddProduct(w, q);
  tau_tau.AddProduct(q, q);
}

std::int64_t Wide96::RoundDivide(std::uint32_t n) const {
  // |value| as three 32-bit limbs, divided limb by limb (64/32 divisions).
  const bool negative = high() < 0;
  std::uint64_t low = this->low();
  auto high = static_cast<std::uint32_t>(this->high());
  if (negative) {
    low = ~low + 1;
    high = ~high + (low == 0 ? 1u : 0u);
  }
  const std::uint64_t limbs[3] = {high, low >> 32, low & 0xFFFFFFFFu};
  std::uint64_t remainder = 0, quotient = 0;
  for (const std::uint64_t limb : limbs) {
    const std::uint64_t part = (remainder << 32) | limb;
    quotient = (quotient << 32) | (part / n);
    remainder = part % n;
  }
  if (2 * remainder >= n) ++quotient;
  return negative ? -static_cast<std::int64_t>(quotient)
                  : static_cast<std::int64_t>(quotient);
}

InterfaceFit SolveInterfaceFit(const InterfaceFitSums& s) {
  InterfaceFit out;
  if (s.count < kMinInterfaceFitSamples) return out;
  const std::uint32_t n = s.count;
  const Mean theta = MeanOf(s.theta, n), omega = MeanOf(s.omega, n),
             tau = MeanOf(s.tau, n);
  const std::int64_t c_tt = Centred(s.theta_theta, theta, theta, n);
  const std::int64_t c_tw = Centred(s.theta_omega, theta, omega, n);
  const std::int64_t c_ww = Centred(s.omega_omega, omega, omega, n);
  const std::int64_t c_tq = Centred(s.theta_tau, theta, tau, n);
  const std::int64_t c_wq = Centred(s.omega_tau, omega, tau, n);
  const std::int64_t c_qq = Centred(s.tau_tau, tau, tau, n);
  if (c_tt <= 0 || c_ww <= 0) {
    out.status = InterfaceFitStatus::kNoMotion;
    return out;
  }

  // Scale each regressor by a power of two so its variance has 29–30 bits. By
  // Cauchy–Schwarz every scaled cross moment is then below 2^30 in magnitude too.
  const int s_t = VarianceShift(c_tt), s_w = VarianceShift(c_ww);
  const int s_q = c_qq > 0 ? VarianceShift(c_qq) : 0;
  Matrix2 a;
  a << Shift(c_tt, 2 * s_t), Shift(c_tw, s_t + s_w), Shift(c_tw, s_t + s_w),
      Shift(c_ww, 2 * s_w);
  const Vector2 r(Shift(c_tq, s_t + s_q), Shift(c_wq, s_w + s_q));
  const std::int64_t a_qq = Shift(c_qq, 2 * s_q);

  // ρ² ≤ 3/4, i.e. det ≥ a11·a22/4: keeps the solution bounded (below) and k_i apart
  // from b_i. Every product here is below 2^61.
  const std::int64_t det = a(0, 0) * a(1, 1) - a(0, 1) * a(1, 0);
  if (4 * det < a(0, 0) * a(1, 1)) {
    out.status = InterfaceFitStatus::kCollinear;
    return out;
  }
  Matrix2 adjugate;
  adjugate << a(1, 1), -a(0, 1), -a(1, 0), a(0, 0);
  const Vector2 num = adjugate.lazyProduct(r);

  // k_i in Q24: α·2^(s_q − s_t + 24), α = num0/det (τ and θ both Q24). b_i in Q24:
  // β·2^(s_q − s_w + 20) (τ Q24 over ω Q20 is 2^4 times the ratio in N·m·s/rad).
  const std::int64_t k = ScaledQuotient(num(0), det, s_q - s_t + 24);
  const std::int64_t b = ScaledQuotient(num(1), det, s_q - s_w + 20);
  const std::int64_t offset =
      FitsInt32(k) && FitsInt32(b)
          ? Offset(tau, theta, omega, static_cast<std::int32_t>(k),
                   static_cast<std::int32_t>(b), n)
          : INT64_MAX;
  if (!FitsInt32(k) || !FitsInt32(b) || !FitsInt32(offset)) {
    out.status = InterfaceFitStatus::kOutOfRange;
    return out;
  }

  // Residual variance in the scaled units, Q26: a_qq − α·r0 − β·r1. With ρ² ≤ 3/4 and
  // the scaled variances in [2^28, 2^30), |α|, |β| ≤ 8·√(a_qq/a_ii) ≤ 16, so α, β in
  // Q26 stay below 2^30 and each product below 2^60.
  const std::int64_t alpha = ScaledQuotient(num(0), det, 26);
  const std::int64_t beta = ScaledQuotient(num(1), det, 26);
  std::int64_t rss = (a_qq << 26) - alpha * r(0) - beta * r(1);
  if (rss < 0) rss = 0;  // rounding of a perfect fit
  // √(rss·2^-26)·2^s_q raw = √rss·2^(s_q − 13).
  const auto root =
      static_cast<std::int64_t>(SquareRoot(static_cast<std::uint64_t>(rss)));
  const std::int64_t rms = Shift(root, 13 - s_q);

  out.status = InterfaceFitStatus::kOk;
  out.stiffness = Stiffness::FromRaw(static_cast<std::int32_t>(k));
  out.damping = Damping::FromRaw(static_cast<std::int32_t>(b));
  out.offset = Torque::FromRaw(static_cast<std::int32_t>(offset));
  out.residual_rms =
      FitsInt32(rms) ? Torque::FromRaw(static_cast<std::int32_t>(rms)) : Torque::Max();
  return out;
}

}  // namespace mjc
