// Little-endian byte access for the fixed layouts of records (calibration record, flash
// store): explicit byte order, no alignment assumptions, the same on host and target.
#pragma once

#include <cstdint>

namespace mjc::protocol {

// Writes the low `bytes` bytes of v at p, least significant first.
constexpr void PutLe(std::uint8_t* p, std::uint64_t v, int bytes) {
  for (int i = 0; i < bytes; ++i) p[i] = static_cast<std::uint8_t>(v >> (8 * i));
}

// Reads `bytes` bytes at p, least significant first.
constexpr std::uint64_t GetLe(const std::uint8_t* p, int bytes) {
  std::uint64_t v = 0;
  for (int i = 0; i < bytes; ++i) v |= static_cast<std::uint64_t>(p[i]) << (8 * i);
  return v;
}

}  // namespace mjc::protocol
