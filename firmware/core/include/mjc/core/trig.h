// Fixed-point sine and cosine of a phase held as an unsigned fraction of a turn.
//
// Phase format: std::uint32_t, 2^32 = one turn (2π rad), so 1 LSB = 2π/2^32 = 1.46e-9
// rad. Every value is a legal angle, unsigned wrap is the 2π wrap (no modulo, no UB),
// and the quadrant is the top two bits. A trajectory steps its phase in exact integer
// ticks (trajectory.h), so a cycle ends on phase 0 without drift.
//
// Output: Coefficient (Q1.30), |result| <= 1.0 = 2^30 raw.
//
// Method. Quarter-wave symmetry reduces any phase to x in [0, 2^30], z = x/2^30, and
// sin(π/2·z) is an odd degree-11 polynomial
//     z·(a1 − w·(m3 − w·(m5 − w·(m7 − w·(m9 − w·m11))))),   w = z²,
// fitted by Remez exchange for minimax absolute error on z in [0, 1]: equal ripple
// 1.33e-11 = 0.014 LSB of Q1.30 (degree 9 would leave 3.3e-9 = 3.6 LSB). All six terms
// of the Horner chain keep one sign (a1, m3 .. m11 > 0 and each partial stays
// positive), so the chain runs in unsigned arithmetic with alternating subtraction. Each
// partial is held in 32 bits in the Q format that fits its magnitude (Q32 .. Q50), so
// every step is one 32x32->64 multiply (UMULL), then a rounding add, a shift by 35..38
// and a subtract on the high word alone; a1 is carried in Q33 and the last product z·P
// in 64 bits. arm-none-eabi-g++ -O2 makes 52 instructions of the whole of Sin(), ~40 on
// the path taken, 7 of them multiplies; no table, no division, and branches only for
// the mirrored quadrants and the exact peak.
//
// Why not a table: linear interpolation to 1 LSB of Q1.30 needs a step below 6e-5 rad,
// ~25,000 entries per quarter wave (100 KB); a cubic-interpolated table costs as many
// multiplies as the polynomial plus the memory loads.
//
// Accuracy against std::sin in double, in LSB of Q1.30 (9.3e-10):
//   |Sin(p) − sin(2π·p/2^32)| <= 0.834 LSB for every p: measured over all 2^30 + 1
//   quarter-wave inputs, which by the exact symmetries below cover every phase (mean
//   error +0.019 LSB). Budget: 0.5 final rounding + 0.125 for P in Q33 + 0.125 for m3
//   + 0.08 for w + 0.014 fit = 0.844. The tests assert <= 1 LSB.
// Exact by construction (bit-identical, tested): Sin(0) = 0, Sin(2^30) = 1,
//   Sin(2^31) = 0, Sin(3·2^30) = −1, Sin(−p) = −Sin(p), Sin(p + 2^31) = −Sin(p),
//   Sin(2^31 − p) = Sin(p), Cos(p) = Sin(p + 2^30), Cos(−p) = Cos(p).
#pragma once

#include <cstdint>

#include "mjc/core/quantities.h"

namespace mjc {

namespace trig_detail {

// Remez coefficients of sin(π/2·z) ≈ z·(a1 − m3·w + m5·w² − m7·w³ + m9·w⁴ − m11·w⁵),
// magnitudes rounded to the Q format named in each constant.
inline constexpr std::uint64_t kA1Q33 = 13493037703u;  // 1.5707963266218763
inline constexpr std::uint32_t kM3Q32 = 2774394652u;   // 0.6459640926527016
inline constexpr std::uint32_t kM5Q35 = 2738216451u;   // 0.07969258733505694
inline constexpr std::uint32_t kM7Q39 = 2573748006u;   // 0.00468162035085393
inline constexpr std::uint32_t kM9Q44 = 2818571606u;   // 0.0001602172464013979
inline constexpr std::uint32_t kM11Q50 = 3848565784u;  // 3.4182130762401213e-06

inline constexpr std::uint32_t kQuarterTurn = std::uint32_t{1} << 30;

// c − round(m·w / 2^kShift): one Horner step, the product rounded half up.
template <int kShift>
constexpr std::uint32_t HornerStep(std::uint32_t c, std::uint32_t m, std::uint32_t w) {
  const std::uint64_t product =
      std::uint64_t{m} * w + (std::uint64_t{1} << (kShift - 1));  // < 2^64
  return c - static_cast<std::uint32_t>(product >> kShift);
}

// sin(π/2 · x/2^30) in Q30 for x in [0, 2^30].
constexpr std::uint32_t QuarterSine(std::uint32_t x) {
  if (x >= kQuarterTurn) return kQuarterTurn;  // the peak: exactly 1.0
  // w = z² in Q32, rounded: z = 4x is Q32 (< 2^32 as z < 1 here) and z² is Q64, whose
  // high word is w; a shift by exactly 32 lets the compiler keep w in one register.
  const std::uint32_t z = x << 2;
  const auto w =
      static_cast<std::uint32_t>((std::uint64_t{z} * z + (std::uint64_t{1} << 31)) >> 32);
  std::uint32_t m = kM11Q50;
  m = HornerStep<38>(kM9Q44, m, w);  // Q50·Q32 = Q82 -> Q44
  m = HornerStep<37>(kM7Q39, m, w);  // Q76 -> Q39
  m = HornerStep<36>(kM5Q35, m, w);  // Q71 -> Q35
  m = HornerStep<35>(kM3Q32, m, w);  // Q67 -> Q32
  // P = a1 − m3·w in Q33, in [1, π/2]: < 2^34.
  const std::uint64_t p =
      kA1Q33 - ((std::uint64_t{m} * w + (std::uint64_t{1} << 30)) >> 31);
  // z·P: x (Q30, < 2^30) · P (Q33, < 2^33.7) = Q63 < 2^63.7, then Q63 -> Q30.
  return static_cast<std::uint32_t>((std::uint64_t{x} * p + (std::uint64_t{1} << 32)) >>
                                    33);
}

}  // namespace trig_detail

// sin(2π · phase / 2^32) in Q1.30. Every phase is legal; error <= 1 LSB (see above).
constexpr Coefficient Sin(std::uint32_t phase) {
  using trig_detail::kQuarterTurn;
  const std::uint32_t offset = phase & (kQuarterTurn - 1u);
  // Quadrants 1 and 3 run the quarter wave backwards: x = 2^30 − offset, in [1, 2^30].
  const bool falling = (phase & kQuarterTurn) != 0;
  const std::uint32_t x = falling ? kQuarterTurn - offset : offset;
  const auto magnitude = static_cast<std::int32_t>(trig_detail::QuarterSine(x));
  // Quadrants 2 and 3 are the negative half wave.
  return Coefficient::FromRaw((phase >> 31) != 0 ? -magnitude : magnitude);
}

// cos(2π · phase / 2^32) in Q1.30 = Sin(phase + quarter turn), wrapping.
constexpr Coefficient Cos(std::uint32_t phase) {
  return Sin(static_cast<std::uint32_t>(phase + trig_detail::kQuarterTurn));
}

struct SineCosine {
  Coefficient sine, cosine;
};

// Sin(phase) and Cos(phase), bit for bit, from the two quarter-wave values of the
// phase's offset in its quadrant (x and 2^30 − x): the quadrant only picks which is
// which and their signs, so it is decoded once instead of once per function.
constexpr SineCosine SinCos(std::uint32_t phase) {
  using trig_detail::kQuarterTurn;
  const std::uint32_t offset = phase & (kQuarterTurn - 1u);
  const auto rising = static_cast<std::int32_t>(trig_detail::QuarterSine(offset));
  const auto falling =
      static_cast<std::int32_t>(trig_detail::QuarterSine(kQuarterTurn - offset));
  const std::uint32_t quadrant = phase >> 30;
  // Quadrants 0 and 2 rise in |sin| (Sin reads x = offset), 1 and 3 fall; the cosine
  // is the sine a quadrant on. Sin is negative in quadrants 2 and 3, Cos in 1 and 2.
  const bool odd = (quadrant & 1u) != 0;
  const std::int32_t sine = odd ? falling : rising;
  const std::int32_t cosine = odd ? rising : falling;
  return {Coefficient::FromRaw(quadrant >= 2 ? -sine : sine),
          Coefficient::FromRaw(quadrant == 1 || quadrant == 2 ? -cosine : cosine)};
}

}  // namespace mjc
