// Signals: a struct field placed at a bit range of a frame's payload (little-endian,
// "Intel" byte order, start bit = least significant bit, as DBC files number them).
// Each message lists its fields once (messages.h); encoders, decoders with range
// checks and the DBC file all come from that list.
#pragma once

#include <array>
#include <concepts>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <type_traits>

#include "mjc/core/fixed.h"

namespace mjc::protocol {

// Which raw values of an enum a decoder accepts. Every enum sent on the bus provides a
// ValidEnumValue overload (found by argument-dependent lookup in its namespace).
template <class E>
concept WireEnum = std::is_enum_v<E> && requires(E e) {
  { ValidEnumValue(e) } -> std::same_as<bool>;
};

namespace signal_detail {

template <class T>
struct Wire;

template <class U, int F, class R>
struct Wire<Fixed<U, F, R>> {
  using Value = Fixed<U, F, R>;
  static constexpr bool kSigned = true;
  static constexpr int kFracBits = F;
  static constexpr std::int64_t ToRaw(Value v) { return v.raw(); }
  static constexpr bool FromRaw(std::int64_t raw, Value* out) {
    if (raw < std::numeric_limits<R>::min() || raw > std::numeric_limits<R>::max()) {
      return false;
    }
    *out = Value::FromRaw(static_cast<R>(raw));
    return true;
  }
};

template <std::integral I>
requires(!std::is_same_v<I, bool>) struct Wire<I> {
  static constexpr bool kSigned = std::is_signed_v<I>;
  static constexpr int kFracBits = 0;
  static constexpr std::int64_t ToRaw(I v) { return static_cast<std::int64_t>(v); }
  static constexpr bool FromRaw(std::int64_t raw, I* out) {
    if constexpr (std::is_signed_v<I>) {
      if (raw < static_cast<std::int64_t>(std::numeric_limits<I>::min()) ||
          raw > static_cast<std::int64_t>(std::numeric_limits<I>::max())) {
        return false;
      }
    } else {
      // Unsigned fields are packed without sign extension, so raw is never negative
      // unless the field is 64 bits wide (then every bit pattern is legal).
      if (sizeof(I) < 8 &&
          (raw < 0 || static_cast<std::uint64_t>(raw) >
                          static_cast<std::uint64_t>(std::numeric_limits<I>::max()))) {
        return false;
      }
    }
    *out = static_cast<I>(raw);
    return true;
  }
};

template <>
struct Wire<bool> {
  static constexpr bool kSigned = false;
  static constexpr int kFracBits = 0;
  static constexpr std::int64_t ToRaw(bool v) { return v ? 1 : 0; }
  static constexpr bool FromRaw(std::int64_t raw, bool* out) {
    if (raw != 0 && raw != 1) return false;
    *out = raw == 1;
    return true;
  }
};

template <WireEnum E>
struct Wire<E> {
  using Under = std::underlying_type_t<E>;
  static constexpr bool kSigned = false;
  static constexpr int kFracBits = 0;
  static constexpr std::int64_t ToRaw(E v) { return static_cast<std::int64_t>(v); }
  static constexpr bool FromRaw(std::int64_t raw, E* out) {
    if (raw < 0 || raw > static_cast<std::int64_t>(std::numeric_limits<Under>::max())) {
      return false;
    }
    const auto e = static_cast<E>(static_cast<Under>(raw));
    if (!ValidEnumValue(e)) return false;
    *out = e;
    return true;
  }
};

}  // namespace signal_detail

// What every signal has, whether it is a field of the message (Signal) or an element of
// an array field (ElementSignal): its place in the payload and its encoding. `Self`
// provides Get(message) and Ref(message) for the field's value.
template <class Self, class Msg, class Field>
struct SignalBase {
  using Wire = signal_detail::Wire<Field>;
  const char* name;     // DBC signal name, with its unit as suffix (motor_angle_rad)
  std::uint16_t start;  // least significant bit, 0..511 (CAN FD frames up to 64 bytes)
  std::uint8_t bits;    // 1..64
  const char* unit;     // DBC unit string

  static constexpr bool kSigned = Wire::kSigned;
  // Physical value = raw · factor (DBC): 2^-F for fixed-point fields, 1 otherwise.
  constexpr double factor() const { return fixed_detail::Pow2(-Wire::kFracBits); }

  // A payload is handled as little-endian 64-bit words: bit k of a word is bit k % 8 of
  // its byte k / 8, the DBC's Intel order. Whole-field shifts and masks, not a loop
  // over bits: Cortex-M4 encodes a telemetry frame in tens of instructions.
  static constexpr std::uint64_t Mask(unsigned n) {
    return n >= 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << n) - 1u;
  }

  // Writes the field into `word`, whose bit 0 is the payload's bit `word_start` (a
  // multiple of 8; 0 for a classical frame's one word).
  constexpr void Pack(const Msg& m, std::uint64_t* word, unsigned word_start = 0) const {
    const unsigned at = start - word_start;
    const std::uint64_t mask = Mask(bits);
    const std::uint64_t raw =
        static_cast<std::uint64_t>(Wire::ToRaw(self().Get(m))) & mask;
    *word = (*word & ~(mask << at)) | (raw << at);
  }

  // Reads the field from `word` (as Pack places it); false when the raw value is not a
  // legal value of the field's type (out of its range, an unknown enum value).
  constexpr bool Unpack(std::uint64_t word, Msg* m, unsigned word_start = 0) const {
    const std::uint64_t raw = (word >> (start - word_start)) & Mask(bits);
    std::int64_t value = static_cast<std::int64_t>(raw);
    if (kSigned && bits < 64 && ((raw >> (bits - 1u)) & 1u)) {
      value = static_cast<std::int64_t>(raw | ~Mask(bits));  // sign-extend
    }
    return Wire::FromRaw(value, &self().Ref(*m));
  }

 private:
  constexpr const Self& self() const { return static_cast<const Self&>(*this); }
};

template <class Msg, class Field>
struct Signal : SignalBase<Signal<Msg, Field>, Msg, Field> {
  Field Msg::*member;
  constexpr const Field& Get(const Msg& m) const { return m.*member; }
  constexpr Field& Ref(Msg& m) const { return m.*member; }
};

// One element of an array field (a batch of samples): `index` of `member`.
template <class Msg, class Field, std::size_t N>
struct ElementSignal : SignalBase<ElementSignal<Msg, Field, N>, Msg, Field> {
  std::array<Field, N> Msg::*member;
  std::size_t index;
  constexpr const Field& Get(const Msg& m) const { return (m.*member)[index]; }
  constexpr Field& Ref(Msg& m) const { return (m.*member)[index]; }
};

template <class Msg, class Field>
constexpr Signal<Msg, Field> MakeSignal(const char* name, Field Msg::*member,
                                        std::uint16_t start, std::uint8_t bits,
                                        const char* unit = "") {
  return {{name, start, bits, unit}, member};
}

template <class Msg, class Field, std::size_t N>
constexpr ElementSignal<Msg, Field, N> MakeSignal(const char* name,
                                                  std::array<Field, N> Msg::*member,
                                                  std::size_t index, std::uint16_t start,
                                                  std::uint8_t bits,
                                                  const char* unit = "") {
  return {{name, start, bits, unit}, member, index};
}

}  // namespace mjc::protocol
