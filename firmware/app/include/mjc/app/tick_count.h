// Consistent reads of what the tick writes, from the main loop it interrupts.
//
// The tick (an interrupt) writes its results in place; the main loop copies them
// between ticks, and a tick may interrupt that copy. The tick counts itself once it has
// written everything; a copy during which the count changed is taken again, so it
// never mixes two ticks (nor tears a 64-bit value, two words on the Cortex-M4). A
// sequence lock reduced to what one core needs: the tick runs to its end before the
// main loop resumes, so the writer is never seen half-way and the count can be even
// or odd alike; the fences only keep the compiler from moving the copy across it.
// (No library offers this: the lock-free containers are for threads, not ISRs.)
#pragma once

#include <atomic>
#include <cstdint>

namespace mjc::app {

class TickCount {
 public:
  // Tick context, after its last write of what readers copy.
  void ISR_Advance() {
    std::atomic_signal_fence(std::memory_order_release);
    count_.store(count_.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
  }

  // Main-loop context: copy() until no tick ran during it; returns that copy.
  template <class Copy>
  auto Read(Copy copy) const {
    std::uint32_t before = count_.load(std::memory_order_relaxed);
    for (;;) {
      std::atomic_signal_fence(std::memory_order_acquire);
      auto value = copy();
      std::atomic_signal_fence(std::memory_order_acquire);
      const std::uint32_t after = count_.load(std::memory_order_relaxed);
      if (after == before) return value;
      before = after;
    }
  }

  std::uint32_t ticks() const { return count_.load(std::memory_order_relaxed); }

 private:
  std::atomic<std::uint32_t> count_{0};
  static_assert(std::atomic<std::uint32_t>::is_always_lock_free);
};

}  // namespace mjc::app
