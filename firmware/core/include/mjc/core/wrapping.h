// Wrap-safe arithmetic for hardware counters (timer counts, tick counters, sequence
// numbers). Signed overflow is undefined behaviour, unsigned wrap is not: counters are
// unsigned, differences go through unsigned subtraction and are read back as the
// two's-complement signed value (defined since C++20).
#pragma once

#include <concepts>
#include <type_traits>

namespace mjc {

// a + b modulo 2^N.
template <std::unsigned_integral T>
constexpr T WrappingAdd(T a, T b) {
  return static_cast<T>(a + b);
}

// a - b modulo 2^N.
template <std::unsigned_integral T>
constexpr T WrappingSub(T a, T b) {
  return static_cast<T>(a - b);
}

// The signed step from `before` to `now` of a free-running N-bit counter: correct as
// long as the true step lies in [-2^(N-1), 2^(N-1)), i.e. the counter moved less than
// half its range between the two reads.
template <std::unsigned_integral T>
constexpr std::make_signed_t<T> WrappingDelta(T now, T before) {
  return static_cast<std::make_signed_t<T>>(WrappingSub(now, before));
}

}  // namespace mjc
