// GPIO pins (RM0440 §9.3, "GPIO functional description"; registers §9.4): mode,
// alternate function, output type, speed, pull; atomic set/reset through BSRR.
//
// A pin is a compile-time value (port, number); a board's pin table (data) lists each
// signal's PinConfig. The tick path uses OutputPin<kPin>, whose set/reset is one store
// to a constant address.
#pragma once

#include <cstdint>

#include "hal/stm32g4/mmio.h"
#include "hal/stm32g4/regs/gpio.h"

namespace mjc::stm32g4 {

enum class Port : std::uint8_t { kA = 0, kB = 1, kC = 2, kD = 3, kE = 4, kF = 5, kG = 6 };

struct Pin {
  Port port = Port::kA;
  std::uint8_t number = 0;  // 0..15
  constexpr bool operator==(const Pin&) const = default;
};

// MODER codes.
enum class PinMode : std::uint8_t {
  kInput = 0,
  kOutput = 1,
  kAlternate = 2,
  kAnalog = 3
};
// OTYPER codes.
enum class OutputType : std::uint8_t { kPushPull = 0, kOpenDrain = 1 };
// OSPEEDR codes (the datasheet gives each one's edge rate per supply and load).
enum class Speed : std::uint8_t { kLow = 0, kMedium = 1, kHigh = 2, kVeryHigh = 3 };
// PUPDR codes.
enum class Pull : std::uint8_t { kNone = 0, kUp = 1, kDown = 2 };

struct PinConfig {
  Pin pin;
  PinMode mode = PinMode::kInput;
  std::uint8_t alternate = 0;  // AF0..AF15, used with kAlternate
  OutputType type = OutputType::kPushPull;
  Speed speed = Speed::kLow;
  Pull pull = Pull::kNone;
  bool initial_high = false;  // kOutput: the level driven from the moment it is output
};

constexpr Address PortAddress(Port port) {
  return gpio::kPortBases[static_cast<std::size_t>(port)];
}

// Configures one pin (read-modify-write of its fields only; the port's clock must be on).
// An output's level is written to BSRR before MODER makes it an output, so it never
// drives the other level even for one cycle. Not for interrupt context: the
// read-modify-writes are not atomic against another writer of the same port's
// registers.
void ConfigurePin(const PinConfig& config);

// Drives a pin that ConfigurePin made an output: one BSRR store (atomic, RM0440 §9.3.4:
// "bit set/reset"), usable from any context.
inline void WritePin(Pin pin, bool high) {
  const unsigned n = pin.number & 15u;
  Write32(PortAddress(pin.port) + gpio::kBsrr,
          high ? gpio::kBs[n].Bit() : gpio::kBr[n].Bit());
}
inline bool ReadPin(Pin pin) {
  return gpio::kId[pin.number & 15u].IsSet(Read32(PortAddress(pin.port) + gpio::kIdr));
}

// A pin by its port's register block address: what tick-path drivers take as a template
// argument (so their pins, like their other blocks, may be placed elsewhere, e.g. in
// RAM for an instruction-count image).
struct PortPin {
  Address port = 0;
  std::uint8_t number = 0;  // 0..15
  constexpr bool operator==(const PortPin&) const = default;
};
constexpr PortPin At(Pin pin) { return {PortAddress(pin.port), pin.number}; }

// The same for a pin fixed at compile time: a constant address and value.
template <PortPin kPin>
struct OutputPin {
  static_assert(kPin.number < 16);
  static constexpr Address kBsrr = kPin.port + gpio::kBsrr;
  static void Set() { Write32(kBsrr, gpio::kBs[kPin.number].Bit()); }
  static void Clear() { Write32(kBsrr, gpio::kBr[kPin.number].Bit()); }
  static void Write(bool high) { high ? Set() : Clear(); }
};

}  // namespace mjc::stm32g4
