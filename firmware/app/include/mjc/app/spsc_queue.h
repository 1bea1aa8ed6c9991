// The application's name for the generic single-producer single-consumer ring
// (mjc/core/spsc_queue.h, shared with the STM32G4 CAN driver).
#pragma once

#include <cstddef>

#include "mjc/core/spsc_queue.h"

namespace mjc::app {

template <class T, std::size_t kCapacity>
using SpscQueue = lockfree::SpscQueue<T, kCapacity>;

}  // namespace mjc::app
