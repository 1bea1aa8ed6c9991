// The chip's 96-bit unique device ID (RM0440 §48.1: three words from 0x1FFF7590, factory
// programmed, read-only), folded to 16 bits: what tells two boards apart on the bus
// (BoardInfo::instance) when they answer with one node id.
#pragma once

#include <cstdint>

#include "hal/stm32g4/mmio.h"

namespace mjc::stm32g4 {

inline constexpr Address kUniqueIdBase = 0x1FFF7590u;

// The unique ID's words XOR-folded to 16 bits. Two chips rarely share it (one in 65,536
// pairs); a duplicate node id is then still told by its interleaved heartbeat ticks.
inline std::uint16_t UniqueId16() {
  std::uint32_t folded = 0;
  for (Address a = kUniqueIdBase; a < kUniqueIdBase + 12; a += 4) folded ^= Read32(a);
  return static_cast<std::uint16_t>(folded ^ (folded >> 16));
}

}  // namespace mjc::stm32g4
