// Single-producer single-consumer ring of fixed capacity, for handing events from the
// control tick (producer, interrupt context) to the main loop (consumer) without a
// heap and without disabling interrupts: each index is written by one side only, and
// 32-bit atomics are single loads/stores on Cortex-M4 (lock-free, no LDREX needed for
// load/store with acquire/release ordering).
#pragma once

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>

namespace mjc::app {

template <class T, std::size_t kCapacity>
class SpscQueue {
  static_assert(kCapacity >= 2 && (kCapacity & (kCapacity - 1)) == 0,
                "capacity must be a power of two (indices wrap by masking)");

 public:
  // Producer side. Returns false (and counts a drop) when full: the producer never
  // waits.
  bool ISR_Push(const T& value) {
    const std::uint32_t head = head_.load(std::memory_order_relaxed);
    const std::uint32_t tail = tail_.load(std::memory_order_acquire);
    if (head - tail == kCapacity) {
      dropped_.store(dropped_.load(std::memory_order_relaxed) + 1,
                     std::memory_order_relaxed);
      return false;
    }
    slots_[head & (kCapacity - 1)] = value;
    head_.store(head + 1, std::memory_order_release);
    return true;
  }

  // Consumer side.
  bool Pop(T* out) {
    const std::uint32_t tail = tail_.load(std::memory_order_relaxed);
    const std::uint32_t head = head_.load(std::memory_order_acquire);
    if (head == tail) return false;
    *out = slots_[tail & (kCapacity - 1)];
    tail_.store(tail + 1, std::memory_order_release);
    return true;
  }

  std::uint32_t dropped() const { return dropped_.load(std::memory_order_relaxed); }

 private:
  std::array<T, kCapacity> slots_{};
  std::atomic<std::uint32_t> head_{0};
  std::atomic<std::uint32_t> tail_{0};
  std::atomic<std::uint32_t> dropped_{0};
};

}  // namespace mjc::app
