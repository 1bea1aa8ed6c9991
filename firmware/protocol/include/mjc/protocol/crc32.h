// CRC-32 (reflected polynomial 0xEDB88320, initial and final XOR 0xFFFFFFFF): the
// zlib/Ethernet CRC, used by the calibration record, the flash stores and the firmware
// image header. Written here because the firmware cannot link zlib; bitwise, so it
// needs no table in flash. Header-only and free of other project headers, so the host's
// image packer can compile it on its own.
//
// One call over a whole buffer (Crc32) or in pieces: Crc32Update over consecutive
// pieces from kCrc32Init, then Crc32Final, gives the same value (the bootloader reads
// an image out of flash a block at a time).
#pragma once

#include <cstdint>
#include <span>

namespace mjc::protocol {

inline constexpr std::uint32_t kCrc32Init = 0xFFFFFFFFu;

constexpr std::uint32_t Crc32Update(std::uint32_t state,
                                    std::span<const std::uint8_t> data) {
  for (const std::uint8_t byte : data) {
    state ^= byte;
    for (int bit = 0; bit < 8; ++bit) {
      state = (state >> 1) ^ (0xEDB88320u & (0u - (state & 1u)));
    }
  }
  return state;
}

constexpr std::uint32_t Crc32Final(std::uint32_t state) { return state ^ 0xFFFFFFFFu; }

constexpr std::uint32_t Crc32(std::span<const std::uint8_t> data) {
  return Crc32Final(Crc32Update(kCrc32Init, data));
}

}  // namespace mjc::protocol
