// Single-producer single-consumer ring of fixed capacity, for handing values between
// the control tick (interrupt context) and the main loop without a heap and without
// disabling interrupts, in either direction: commands main loop → tick, events tick →
// main loop, CAN frames main loop → transmit interrupt. Each index is written by one
// side only, and 32-bit atomics are single loads/stores on Cortex-M4 (lock-free, no
// LDREX needed for load/store with acquire/release ordering). Generic, so it lives
// below both users: the application (mjc::app::SpscQueue names it) and the STM32G4 CAN
// driver (received frames, interrupt → main loop), which must not depend on the app.
#pragma once

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>

namespace mjc::lockfree {

template <class T, std::size_t kCapacity>
class SpscQueue {
  static_assert(kCapacity >= 2 && (kCapacity & (kCapacity - 1)) == 0,
                "capacity must be a power of two (indices wrap by masking)");

 public:
  // Producer side. Returns false (and counts a drop) when full: the producer never
  // waits.
  bool Push(const T& value) {
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

  // Consumer side, in place: the oldest value (nullptr when empty), valid until
  // DropFront(). Saves the copy Pop() makes, and costs two loads when empty.
  const T* Front() const {
    const std::uint32_t tail = tail_.load(std::memory_order_relaxed);
    const std::uint32_t head = head_.load(std::memory_order_acquire);
    return head == tail ? nullptr : &slots_[tail & (kCapacity - 1)];
  }
  // Releases the value Front() returned (which must not have been nullptr).
  void DropFront() {
    tail_.store(tail_.load(std::memory_order_relaxed) + 1, std::memory_order_release);
  }

  std::uint32_t dropped() const { return dropped_.load(std::memory_order_relaxed); }

 private:
  std::array<T, kCapacity> slots_{};
  std::atomic<std::uint32_t> head_{0};
  std::atomic<std::uint32_t> tail_{0};
  std::atomic<std::uint32_t> dropped_{0};
};

}  // namespace mjc::lockfree
