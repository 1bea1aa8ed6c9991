// Fixed-point quantities: a signed integer that carries its unit and its Q format.
//
// Fixed<U, F, Rep> holds value = raw · 2^-F in unit U. The rules (docs/CONVENTIONS.md):
//  - add / subtract only the same unit in the same format; the result saturates;
//  - a product is exact: Fixed<U1,F1,R1> * Fixed<U2,F2,R2> is a Fixed<U1·U2, F1+F2> in
//    the wide representation (int32 for 16-bit operands, int64 for 32-bit ones), and
//    FixedCast<To>() brings it to the wanted format, rounding to nearest (ties toward
//    +inf, i.e. floor(x + ½ LSB)) and saturating. Mul<To>() does both in one call;
//  - Divide<To>(a, b) divides through int64, rounds to nearest (ties away from zero)
//    and saturates; b = 0 saturates toward the sign of a (0/0 gives 0);
//  - FromDouble() is consteval: a literal never puts a float on the target's hot path.
//    Quantize() is the run-time form for host code (tools, simulator, tests);
//  - every conversion that can lose range or precision is spelled out.
//
// All operations are constexpr and rely only on C++20's defined two's-complement
// arithmetic and shifts, so the same inputs give bit-identical outputs on x86-64 and
// Cortex-M4 (tests/target compares a digest of both).
#pragma once

#include <compare>
#include <concepts>
#include <cstdint>
#include <limits>
#include <type_traits>

#include "mjc/core/units.h"

namespace mjc {

namespace fixed_detail {

// The number of significant bits of v (0 for 0).
constexpr int BitLength(std::uint64_t v) {
  int n = 0;
  for (; v != 0; v >>= 1) ++n;
  return n;
}

template <class Rep>
inline constexpr int kBits = std::numeric_limits<Rep>::digits + 1;

// The representation that holds any product of two operands exactly.
template <class A, class B>
using WideRep =
    std::conditional_t<(sizeof(A) <= 2 && sizeof(B) <= 2), std::int32_t, std::int64_t>;

template <class Rep>
constexpr Rep SaturateTo(std::int64_t v) {
  // One test for the common case, a value that fits (on Cortex-M4 a compare of the high
  // word with the low word's sign, not two 64-bit compares).
  const auto narrow = static_cast<Rep>(v);
  if (narrow == v) return narrow;
  return v < 0 ? std::numeric_limits<Rep>::min() : std::numeric_limits<Rep>::max();
}

// floor(v / 2^s + 1/2) without overflow, for 0 < s < 64.
constexpr std::int64_t RoundingShiftRight(std::int64_t v, int s) {
  // floor(v / 2^s) (arithmetic shift is defined in C++20), plus one when the remainder
  // v mod 2^s is at least half, i.e. exactly when bit s−1 of v is set. quotient <=
  // INT64_MAX >> s, so the increment cannot overflow.
  const std::int64_t quotient = v >> s;
  return quotient + ((v >> (s - 1)) & 1);
}

// SaturateTo<int32>(RoundingShiftRight(v, s)) for |v| <= 2^62 (a product of two int32s)
// and 0 < s < 32, in 32-bit words: r = v + 2^(s−1) cannot overflow, r >> s is the
// rounded value, and it fits int32 exactly when r's high word h lies in
// [−2^(s−1), 2^(s−1)), i.e. when h >> (s−1) is 0 or −1 and then equal to the sign of the
// low word q of r >> s (out of range it is neither 0 nor −1). On Cortex-M4 that is
// SMULL, ADDS, ADC, LSR, ORR, ASR, CMP and a branch, two instructions fewer than the
// 64-bit form (GCC kept the high word of r >> s for the saturation).
constexpr std::int32_t RoundingShiftRightProduct(std::int64_t v, int s) {
  const std::int64_t r = v + (std::int64_t{1} << (s - 1));
  const auto high = static_cast<std::int32_t>(r >> 32);
  const auto low = static_cast<std::uint32_t>(static_cast<std::uint64_t>(r));
  const auto q = static_cast<std::int32_t>(
      (low >> s) | (static_cast<std::uint32_t>(high) << (32 - s)));
  if ((high >> (s - 1)) == (q >> 31)) return q;
  return high < 0 ? std::numeric_limits<std::int32_t>::min()
                  : std::numeric_limits<std::int32_t>::max();
}

// RoundingShiftRightProduct for a product whose rounded value the caller has proved
// to fit int32 (a magnitude bound stated where it is called): no saturation test, on
// Cortex-M4 three instructions fewer.
constexpr std::int32_t RoundingShiftRightProductInRange(std::int64_t v, int s) {
  const std::int64_t r = v + (std::int64_t{1} << (s - 1));
  const auto high = static_cast<std::uint32_t>(static_cast<std::uint64_t>(r) >> 32);
  const auto low = static_cast<std::uint32_t>(static_cast<std::uint64_t>(r));
  return static_cast<std::int32_t>((low >> s) | (high << (32 - s)));
}

// v clamped to the signed range of `kBits` bits, [−2^(kBits−1), 2^(kBits−1) − 1], for
// 1 < kBits < 32: SSAT on the Cortex-M4 (one instruction; GCC wrote the two compares
// out as four).
template <int kBits>
constexpr std::int32_t SaturateToBits(std::int32_t v) {
  static_assert(kBits > 1 && kBits < 32);
#if defined(__arm__) && defined(__ARM_FEATURE_SAT)
  if (!std::is_constant_evaluated()) {
    std::int32_t r = 0;
    asm("ssat %0, %1, %2" : "=r"(r) : "I"(kBits), "r"(v));
    return r;
  }
#endif
  constexpr std::int32_t kMax = (std::int32_t{1} << (kBits - 1)) - 1;
  return v > kMax ? kMax : (v < -kMax - 1 ? -kMax - 1 : v);
}

// v · 2^s, saturated to int64, for 0 <= s < 63.
constexpr std::int64_t SaturatingShiftLeft(std::int64_t v, int s) {
  if (s == 0) return v;
  if (v > (std::numeric_limits<std::int64_t>::max() >> s)) {
    return std::numeric_limits<std::int64_t>::max();
  }
  if (v < (std::numeric_limits<std::int64_t>::min() >> s)) {
    return std::numeric_limits<std::int64_t>::min();
  }
  return v << s;
}

// Not constexpr: reaching it during constant evaluation is a compile error, which is
// how a consteval literal reports a value outside its format (no exceptions on target).
// a·b, exact in int64. On Cortex-M4 this is one SMULL, written out because GCC, when an
// operand comes out of a saturating add's branches, widens it to 64 bits first and then
// multiplies 64×64 (three multiplies and an add); the products are the same.
constexpr std::int64_t WideProduct(std::int32_t a, std::int32_t b) {
#if defined(__arm__) && defined(__ARM_FEATURE_DSP)
  if (!std::is_constant_evaluated()) {
    std::uint32_t lo = 0;
    std::int32_t hi = 0;
    asm("smull %0, %1, %2, %3" : "=&r"(lo), "=&r"(hi) : "r"(a), "r"(b));
    return static_cast<std::int64_t>((static_cast<std::uint64_t>(hi) << 32) | lo);
  }
#endif
  return std::int64_t{a} * b;
}

void LiteralOutOfRange();

constexpr double Pow2(int e) {
  double r = 1.0;
  for (int i = 0; i < e; ++i) r *= 2.0;
  for (int i = 0; i > e; --i) r *= 0.5;
  return r;
}

}  // namespace fixed_detail

template <class U, int kFrac, std::signed_integral Rep = std::int32_t>
class Fixed {
 public:
  using unit = U;
  using rep = Rep;
  static constexpr int kFracBits = kFrac;
  static constexpr int kBits = fixed_detail::kBits<Rep>;
  static_assert(kFrac >= 0 && kFrac < kBits, "fraction bits must fit the representation");

  // Zero.
  constexpr Fixed() = default;

  // An integer value (not a raw count), saturated to the format's range. Eigen builds
  // its zeros and identities through Scalar(0) and Scalar(1).
  template <std::integral I>
  explicit constexpr Fixed(I whole)
      : raw_(fixed_detail::SaturateTo<Rep>(fixed_detail::SaturatingShiftLeft(
            static_cast<std::int64_t>(whole), kFrac))) {}

  // Same unit, another format: rounds to nearest and saturates (see FixedCast).
  template <int kOtherFrac, class OtherRep>
  requires(
      kOtherFrac != kFrac ||
      !std::is_same_v<
          OtherRep, Rep>) explicit constexpr Fixed(Fixed<U, kOtherFrac, OtherRep> other);

  static constexpr Fixed FromRaw(Rep raw) {
    Fixed f;
    f.raw_ = raw;
    return f;
  }

  // Compile-time literal: rounds to nearest (ties away from zero); a value outside the
  // format's range is a compile error.
  static consteval Fixed FromDouble(double value) {
    const double scaled = value * fixed_detail::Pow2(kFrac);
    if (!(scaled < kLimit && scaled >= -kLimit)) {
      fixed_detail::LiteralOutOfRange();
    }
    return FromRaw(RoundScaled(scaled));
  }

  // Run-time quantisation for host code: rounds to nearest (ties away from zero),
  // saturates out-of-range values, maps NaN to zero.
  static constexpr Fixed Quantize(double value) {
    const double scaled = value * fixed_detail::Pow2(kFrac);
    if (scaled != scaled) return Fixed{};
    if (scaled >= kLimit) return Max();
    if (scaled < -kLimit) return Min();
    return FromRaw(RoundScaled(scaled));
  }

  static constexpr Fixed Max() { return FromRaw(std::numeric_limits<Rep>::max()); }
  static constexpr Fixed Min() { return FromRaw(std::numeric_limits<Rep>::min()); }
  // One LSB.
  static constexpr Fixed Epsilon() { return FromRaw(1); }

  constexpr Rep raw() const { return raw_; }
  constexpr double ToDouble() const {
    return static_cast<double>(raw_) * fixed_detail::Pow2(-kFrac);
  }

  // Saturating: -Min() is Max().
  constexpr Fixed operator-() const {
    return raw_ == std::numeric_limits<Rep>::min() ? Max()
                                                   : FromRaw(static_cast<Rep>(-raw_));
  }
  constexpr Fixed operator+() const { return *this; }

  constexpr Fixed& operator+=(Fixed o) { return *this = *this + o; }
  constexpr Fixed& operator-=(Fixed o) { return *this = *this - o; }

  friend constexpr Fixed operator+(Fixed a, Fixed b) {
    Rep r{};
    if (__builtin_add_overflow(a.raw_, b.raw_, &r)) {
      return b.raw_ > 0 ? Max() : Min();
    }
    return FromRaw(r);
  }
  friend constexpr Fixed operator-(Fixed a, Fixed b) {
    Rep r{};
    if (__builtin_sub_overflow(a.raw_, b.raw_, &r)) {
      return b.raw_ < 0 ? Max() : Min();
    }
    return FromRaw(r);
  }

  // Scaling by an integer count, saturating.
  template <std::integral I>
  friend constexpr Fixed operator*(Fixed a, I n) {
    Rep r{};
    if (__builtin_mul_overflow(a.raw_, n, &r)) {
      return ((a.raw_ < 0) != (n < 0)) ? Min() : Max();
    }
    return FromRaw(r);
  }
  template <std::integral I>
  friend constexpr Fixed operator*(I n, Fixed a) {
    return a * n;
  }

  friend constexpr auto operator<=>(Fixed, Fixed) = default;
  friend constexpr bool operator==(Fixed, Fixed) = default;

 private:
  // 2^(bits-1) as a double: the first scaled value that no longer fits.
  static constexpr double kLimit = fixed_detail::Pow2(kBits - 1);

  static constexpr Rep RoundScaled(double scaled) {
    // |scaled| < 2^(bits-1): the truncating cast is defined; adjust to nearest.
    auto t = static_cast<std::int64_t>(scaled);
    const double rest = scaled - static_cast<double>(t);
    if (rest >= 0.5) ++t;
    if (rest <= -0.5) --t;
    return fixed_detail::SaturateTo<Rep>(t);
  }

  Rep raw_ = 0;
};

template <class T>
struct IsFixed : std::false_type {};
template <class U, int F, class R>
struct IsFixed<Fixed<U, F, R>> : std::true_type {};
template <class T>
concept FixedPoint = IsFixed<T>::value;

// Same unit, any format to any format: rounds to nearest (ties toward +inf) when
// fraction bits are dropped, saturates when the value does not fit.
template <FixedPoint To, class U, int F, class R>
constexpr To FixedCast(Fixed<U, F, R> x) {
  static_assert(std::is_same_v<typename To::unit, U>,
                "FixedCast changes format, never unit");
  constexpr int kShift = To::kFracBits - F;
  std::int64_t v = x.raw();
  if constexpr (kShift > 0) {
    v = fixed_detail::SaturatingShiftLeft(v, kShift);
  } else if constexpr (kShift < 0) {
    v = fixed_detail::RoundingShiftRight(v, -kShift);
  }
  return To::FromRaw(fixed_detail::SaturateTo<typename To::rep>(v));
}

template <class U, int kFrac, std::signed_integral Rep>
template <int kOtherFrac, class OtherRep>
requires(kOtherFrac != kFrac || !std::is_same_v<OtherRep, Rep>) constexpr Fixed<
    U, kFrac, Rep>::Fixed(Fixed<U, kOtherFrac, OtherRep> other)
    : raw_(FixedCast<Fixed>(other).raw()) {}

// Exact product in the wide representation. 64-bit operands are refused: Cortex-M4 has
// no 128-bit type, so shift a wide value down (FixedCast) before multiplying it again.
template <class U1, int F1, class R1, class U2, int F2, class R2>
constexpr auto operator*(Fixed<U1, F1, R1> a, Fixed<U2, F2, R2> b) {
  static_assert(sizeof(R1) <= 4 && sizeof(R2) <= 4,
                "multiply 32-bit (or narrower) operands; FixedCast a 64-bit value first");
  using W = fixed_detail::WideRep<R1, R2>;
  using Result = Fixed<UnitProduct<U1, U2>, F1 + F2, W>;
  if constexpr (std::is_same_v<W, std::int64_t>) {
    return Result::FromRaw(fixed_detail::WideProduct(a.raw(), b.raw()));
  } else {
    return Result::FromRaw(
        static_cast<W>(static_cast<W>(a.raw()) * static_cast<W>(b.raw())));
  }
}

// a · b rounded to nearest and saturated into To, whose unit must be the product's.
template <FixedPoint To, class A, class B>
constexpr To Mul(A a, B b) {
  const auto product = a * b;
  using Product = decltype(product);
  constexpr int kShift = Product::kFracBits - To::kFracBits;
  if constexpr (kShift > 0 && kShift < 32 &&
                std::is_same_v<typename Product::rep, std::int64_t> &&
                std::is_same_v<typename To::rep, std::int32_t>) {
    // FixedCast's value: a product of 32-bit operands has |raw| <= 2^62.
    static_assert(std::is_same_v<typename To::unit, typename Product::unit>,
                  "Mul: the result's unit must be the product's");
    return To::FromRaw(fixed_detail::RoundingShiftRightProduct(product.raw(), kShift));
  } else {
    return FixedCast<To>(product);
  }
}

// Mul<To>(a, b) for 32-bit operands whose rounded product the caller has proved to
// fit To (say why where it is called): the same value without the saturation test.
template <FixedPoint To, class A, class B>
constexpr To MulInRange(A a, B b) {
  const auto product = a * b;
  using Product = decltype(product);
  constexpr int kShift = Product::kFracBits - To::kFracBits;
  static_assert(kShift > 0 && kShift < 32 &&
                    std::is_same_v<typename Product::rep, std::int64_t> &&
                    std::is_same_v<typename To::rep, std::int32_t>,
                "MulInRange: 32-bit operands, an int32 result, a shift of 1..31");
  static_assert(std::is_same_v<typename To::unit, typename Product::unit>,
                "MulInRange: the result's unit must be the product's");
  return To::FromRaw(
      fixed_detail::RoundingShiftRightProductInRange(product.raw(), kShift));
}

// a / b into To (unit U_a / U_b), through int64, rounded to nearest with ties away from
// zero and saturated. b = 0 yields Max() for a > 0, Min() for a < 0 and zero for a = 0.
// The format must satisfy 0 <= F_to + F_b - F_a <= 31 so the scaled dividend is exact.
template <FixedPoint To, class U1, int F1, class R1, class U2, int F2, class R2>
constexpr To Divide(Fixed<U1, F1, R1> a, Fixed<U2, F2, R2> b) {
  static_assert(std::is_same_v<typename To::unit, UnitQuotient<U1, U2>>,
                "Divide: the result's unit must be U_a / U_b");
  static_assert(sizeof(R1) <= 4 && sizeof(R2) <= 4, "Divide takes 32-bit operands");
  constexpr int kShift = To::kFracBits + F2 - F1;
  static_assert(kShift >= 0 && kShift <= 31, "Divide: choose formats with 0..31 shift");
  using ToRep = typename To::rep;
  const std::int64_t n = static_cast<std::int64_t>(a.raw()) * (std::int64_t{1} << kShift);
  const std::int64_t d = b.raw();
  if (d == 0) {
    if (n == 0) return To{};
    return n > 0 ? To::Max() : To::Min();
  }
  const bool negative = (n < 0) != (d < 0);
  const std::uint64_t un =
      n < 0 ? 0u - static_cast<std::uint64_t>(n) : static_cast<std::uint64_t>(n);
  const std::uint64_t ud =
      d < 0 ? 0u - static_cast<std::uint64_t>(d) : static_cast<std::uint64_t>(d);
  const std::uint64_t q = (un + ud / 2u) / ud;  // un < 2^62, no overflow
  const std::int64_t sq =
      negative ? -static_cast<std::int64_t>(q) : static_cast<std::int64_t>(q);
  return To::FromRaw(fixed_detail::SaturateTo<ToRep>(sq));
}

namespace fixed_detail {
// MulShiftRound for a signed multiplier, or for an unsigned one below 2^31 (whose low
// word's product is then one UMULL: a signed one needs a correction for its sign).
template <class M>
constexpr std::int64_t MulShiftRoundImpl(std::int64_t a, M m, int shift) {
  // a = hi·2^32 + lo with hi signed and 0 <= lo < 2^32.
  // hi held in 32 bits: a 32×32 multiply (SMULL), not a 64×64 one.
  const auto hi = static_cast<std::int32_t>(a >> 32);
  const auto lo = static_cast<std::uint32_t>(static_cast<std::uint64_t>(a) & 0xFFFFFFFFu);
  // |hi·m| < 2^62 and |lo·m| < 2^63.
  const std::int64_t hi_product = WideProduct(hi, static_cast<std::int32_t>(m));
  std::int64_t lo_product = 0;
  if constexpr (std::is_unsigned_v<M>) {
    lo_product = static_cast<std::int64_t>(std::uint64_t{lo} * m);
  } else {
    lo_product = static_cast<std::int64_t>(lo) * m;
  }
  // a·m = hi_product·2^32 + lo_product = upper·2^32 + lower, 0 <= lower < 2^32.
  const std::int64_t upper = hi_product + (lo_product >> 32);
  const auto lower =
      static_cast<std::uint32_t>(static_cast<std::uint64_t>(lo_product) & 0xFFFFFFFFu);
  if (shift == 32) {
    return lower >= 0x80000000u ? upper + 1 : upper;
  }
  // shift > 32: the rounding half 2^(shift-1) lies wholly in `upper`, and `lower` is
  // below one unit of the result, so floor((upper·2^32 + lower + half) / 2^shift) =
  // floor((upper + 2^(shift-33)) / 2^(shift-32)).
  // s = shift − 32 is 1..30: the half fits 32 bits and the shift moves each 32-bit word
  // once (a 64-bit shift by a register would also provide for shifts of 32 or more).
  const int s = shift - 32;
  const std::int64_t half = std::uint32_t{1} << (s - 1);
  const std::int64_t rounded = upper + half;  // |upper| < 2^62.1: no overflow
  const auto rounded_hi = static_cast<std::int32_t>(rounded >> 32);
  const auto rounded_lo = static_cast<std::uint32_t>(static_cast<std::uint64_t>(rounded));
  const std::uint32_t result_lo =
      (rounded_lo >> s) | (static_cast<std::uint32_t>(rounded_hi) << (32 - s));
  const std::int64_t result_hi = rounded_hi >> s;
  return static_cast<std::int64_t>((static_cast<std::uint64_t>(result_hi) << 32) |
                                   result_lo);
}

}  // namespace fixed_detail

// floor(a · m / 2^shift + 1/2), computed exactly through a 96-bit
// intermediate built from two 32×32→64 products (Cortex-M4 has SMULL/UMULL but no
// 128-bit type). For scaling wide sums by a constant: energy readout (Σ P / f_tick),
// the velocity estimator's 1/(D·dt). Legal shift: 32..62.
constexpr std::int64_t MulShiftRound(std::int64_t a, std::int32_t m, int shift) {
  return fixed_detail::MulShiftRoundImpl(a, m, shift);
}

// MulShiftRound for a multiplier known to lie in [0, 2^31) (the velocity estimator's
// scale): the same value, two Cortex-M4 instructions fewer.
constexpr std::int64_t MulShiftRoundUnsigned(std::int64_t a, std::uint32_t m, int shift) {
  return fixed_detail::MulShiftRoundImpl(a, m, shift);
}

// |x|, saturating (Abs(Min()) is Max()).
template <class U, int F, class R>
constexpr Fixed<U, F, R> Abs(Fixed<U, F, R> x) {
  return x.raw() < 0 ? -x : x;
}

template <class U, int F, class R>
constexpr Fixed<U, F, R> Clamp(Fixed<U, F, R> x, Fixed<U, F, R> lo, Fixed<U, F, R> hi) {
  return x < lo ? lo : (hi < x ? hi : x);
}

}  // namespace mjc
