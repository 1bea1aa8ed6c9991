// What every register model of the virtual STM32G474 shares: virtual time in
// picoseconds, the list of rule violations, the shape of one bus access, and the
// peripheral interface the chip's address decoder dispatches to.
//
// Time is an integer count of picoseconds (2^63 ps ≈ 106 days of virtual time) so that
// clocks that do not divide each other (170 MHz, 32 kHz, bit times) never drift: each
// clock converts elapsed picoseconds to whole ticks and carries the remainder exactly
// (TickCounter).
#pragma once

#include <cstdint>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

namespace mjc::g474model {

using Picoseconds = std::int64_t;
inline constexpr Picoseconds kNever = std::numeric_limits<Picoseconds>::max();
inline constexpr Picoseconds kPsPerSecond = 1'000'000'000'000;

constexpr Picoseconds Microseconds(double us) {
  return static_cast<Picoseconds>(us * 1e6);
}
constexpr Picoseconds Nanoseconds(double ns) {
  return static_cast<Picoseconds>(ns * 1e3);
}

// A rule of the manual (or of an attached device's datasheet) that the code driving the
// chip broke. The chip keeps running as the silicon would (usually by ignoring the
// access or misbehaving the way the manual says); the violation is what a test or the
// virtual board checks.
struct Violation {
  Picoseconds time_ps = 0;
  std::string source;  // "RCC", "FLASH", "AS5047P", "bus", …
  std::string what;    // the rule and what was done, with the manual's section
};

class ViolationLog {
 public:
  void Report(Picoseconds now, std::string source, std::string what) {
    entries_.push_back({now, std::move(source), std::move(what)});
  }
  const std::vector<Violation>& entries() const { return entries_; }
  bool empty() const { return entries_.empty(); }
  void Clear() { entries_.clear(); }
  // True when some entry's source is `source` and its text contains `needle`.
  bool Contains(const std::string& source, const std::string& needle) const {
    for (const auto& v : entries_) {
      if (v.source == source && v.what.find(needle) != std::string::npos) return true;
    }
    return false;
  }
  std::string ToString() const {
    std::string s;
    for (const auto& v : entries_) {
      s += "[" + std::to_string(v.time_ps / 1000) + " ns] " + v.source + ": " + v.what +
           "\n";
    }
    return s;
  }

 private:
  std::vector<Violation> entries_;
};

// One bus access as a model sees it: the 32-bit register at `offset` (4-aligned), the
// bytes touched (`mask`), the written value already shifted into place, and the width
// the CPU used (2 or 4; the SPI data register cares).
struct Access {
  std::uint32_t offset = 0;
  std::uint32_t mask = 0xFFFFFFFFu;
  std::uint32_t value = 0;
  unsigned bytes = 4;
  // Writes `value` into `reg` for the bits in `writable` that this access touches.
  void Apply(std::uint32_t* reg, std::uint32_t writable = 0xFFFFFFFFu) const {
    const std::uint32_t m = mask & writable;
    *reg = (*reg & ~m) | (value & m);
  }
  // The written value with untouched bytes taken from `current`.
  std::uint32_t Merged(std::uint32_t current) const {
    return (current & ~mask) | (value & mask);
  }
};

// Converts elapsed virtual time to whole ticks of a clock of `hz`, carrying the
// remainder so that no tick is ever lost or invented across calls.
class TickCounter {
 public:
  // Ticks elapsed in `dt` at `hz` (0 when hz is 0: a stopped clock).
  std::uint64_t Advance(Picoseconds dt, double hz) {
    if (dt <= 0 || hz <= 0) return 0;
    return Advance(dt, static_cast<std::uint64_t>(hz));
  }
  // The same for a clock already in whole hertz (what the double's truncation gives).
  std::uint64_t Advance(Picoseconds dt, std::uint64_t f64) {
    if (dt <= 0 || f64 == 0) return 0;
    if (dt < (Picoseconds{1} << 31) && f64 < (std::uint64_t{1} << 32)) {
      // The common case (one register access, a clock below 4.3 GHz): the product and
      // the remainder (< 10^12 < 2^40) fit 64 bits, and so does their sum; the same
      // arithmetic as below, without 128-bit division.
      const auto sum =
          static_cast<std::uint64_t>(remainder_) + static_cast<std::uint64_t>(dt) * f64;
      remainder_ = sum % static_cast<std::uint64_t>(kPsPerSecond);
      return sum / static_cast<std::uint64_t>(kPsPerSecond);
    }
    const auto f = static_cast<unsigned __int128>(f64);
    remainder_ += static_cast<unsigned __int128>(dt) * f;
    const auto ticks = remainder_ / kPsPerSecond;
    remainder_ %= kPsPerSecond;
    return static_cast<std::uint64_t>(ticks);
  }
  // Time from now until `ticks` more ticks have elapsed at `hz`.
  Picoseconds UntilTicks(std::uint64_t ticks, double hz) const {
    if (hz <= 0) return kNever;
    return UntilTicks(ticks, static_cast<std::uint64_t>(hz));
  }
  Picoseconds UntilTicks(std::uint64_t ticks, std::uint64_t f64) const {
    if (f64 == 0) return kNever;
    if (ticks < (std::uint64_t{1} << 24) && f64 < (std::uint64_t{1} << 32)) {
      // ticks × 10^12 < 2^64, and so is what is added to it: 64-bit arithmetic.
      const std::uint64_t need = ticks * static_cast<std::uint64_t>(kPsPerSecond);
      const auto rest = static_cast<std::uint64_t>(remainder_);
      if (need <= rest) return 0;
      return static_cast<Picoseconds>((need - rest + f64 - 1) / f64);
    }
    const auto f = static_cast<unsigned __int128>(f64);
    const unsigned __int128 need = static_cast<unsigned __int128>(ticks) * kPsPerSecond;
    if (need <= remainder_) return 0;
    const unsigned __int128 ps = (need - remainder_ + f - 1) / f;
    if (ps > static_cast<unsigned __int128>(kNever)) return kNever;
    return static_cast<Picoseconds>(ps);
  }
  void Reset() { remainder_ = 0; }

 private:
  unsigned __int128 remainder_ = 0;
};

// A peripheral block as the address decoder sees it. Offsets are from the block's base.
class Peripheral {
 public:
  virtual ~Peripheral() = default;
  // Returns false when `a.offset` is reserved in this block (the decoder reports it).
  virtual bool Read(const Access& a, std::uint32_t* value) = 0;
  virtual bool Write(const Access& a) = 0;
  // The block's registers back to their reset values (a system reset or the RCC's
  // peripheral reset bit).
  virtual void Reset() = 0;
  // Brings the model's state to virtual time `now` (monotonic). Called before every
  // access to any block, so models can be lazy.
  virtual void Advance(Picoseconds /*now*/) {}
  // The earliest future time at which the model changes something software could see
  // (a flag, an interrupt line), or kNever. WFI jumps to the smallest of these.
  virtual Picoseconds NextEvent() const { return kNever; }
  // The block's clock (RCC enable bit) on or off: a stopped block does not count.
  void SetClockOn(bool on) { clock_on_ = on; }
  bool clock_on() const { return clock_on_; }

 protected:
  bool clock_on_ = true;
};

// A register value or address as the manual writes it, for the violation reports
// ("0x08004000").
inline std::string Hex(std::uint32_t v) {
  char b[16];
  std::snprintf(b, sizeof b, "0x%08X", v);
  return b;
}

// Even parity helper used by the AS5047P frames.
constexpr bool OddBitCount(std::uint32_t v) {
  v ^= v >> 16;
  v ^= v >> 8;
  v ^= v >> 4;
  v ^= v >> 2;
  v ^= v >> 1;
  return (v & 1u) != 0;
}

}  // namespace mjc::g474model
