// The signal chain's tests rebuild the tick's alignment from its parts: torque and
// segment delayed by the velocity estimator's group delay. The tick itself keeps one
// ring of its own (ControlTick::delayed_), so this stays with the tests.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

namespace mjc {

// A fixed delay of int32 samples in caller-owned storage: delay() = storage.size().
class DelayLine {
 public:
  explicit DelayLine(std::span<std::int32_t> storage) : storage_(storage) {}

  // Sets every slot, so the next delay() pushes return `value`.
  void Fill(std::int32_t value) {
    for (auto& slot : storage_) slot = value;
    next_ = 0;
  }

  // Stores `value` and returns the one pushed delay() ticks ago.
  std::int32_t Push(std::int32_t value) {
    if (storage_.empty()) return value;
    const std::int32_t oldest = storage_[next_];
    storage_[next_] = value;
    next_ = next_ + 1 == storage_.size() ? 0 : next_ + 1;
    return oldest;
  }

  std::size_t delay() const { return storage_.size(); }

 private:
  std::span<std::int32_t> storage_;
  std::size_t next_ = 0;
};

}  // namespace mjc
