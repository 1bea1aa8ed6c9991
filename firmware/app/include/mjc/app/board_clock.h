// The board's clock as the main loop keeps it: the control tick's counter, and whole
// milliseconds derived from it exactly (the remainder carried, so exact at any tick
// rate; the millisecond clock wraps on its own, not when the tick counter does).
#pragma once

#include <cstdint>

namespace mjc::app {

class BoardClock {
 public:
  // The tick the last control tick reported, at `tick_hz`.
  void Advance(std::uint32_t tick, std::uint32_t tick_hz) {
    const std::uint64_t scaled = std::uint64_t{tick - ticks_} * 1000u + remainder_;
    ms_ += static_cast<std::uint32_t>(scaled / tick_hz);
    remainder_ = static_cast<std::uint32_t>(scaled % tick_hz);
    ticks_ = tick;
  }
  std::uint32_t ticks() const { return ticks_; }
  std::uint32_t ms() const { return ms_; }

  // At least `ms` (rounded up) in ticks.
  static std::uint32_t TicksFromMs(std::uint32_t ms, std::uint32_t tick_hz) {
    return static_cast<std::uint32_t>((std::uint64_t{ms} * tick_hz + 999u) / 1000u);
  }

 private:
  std::uint32_t ticks_ = 0;
  std::uint32_t ms_ = 0;
  std::uint32_t remainder_ = 0;  // tick·1000 not yet a whole millisecond, < tick rate
};

// A message's cadence on the board's clock: due every tick_hz / hz ticks (at most every
// tick), at once after Now(); never at 0 Hz.
class Cadence {
 public:
  bool Due(std::uint32_t now, std::uint16_t hz, std::uint32_t tick_hz) {
    if (hz == 0) return false;
    if (static_cast<std::int32_t>(now - next_) < 0) return false;
    const std::uint32_t period = tick_hz / hz;
    next_ = now + (period == 0 ? 1u : period);
    return true;
  }
  void Now(std::uint32_t now) { next_ = now; }

 private:
  std::uint32_t next_ = 0;
};

}  // namespace mjc::app
