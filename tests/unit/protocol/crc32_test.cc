// The firmware's CRC-32 against zlib's crc32 (an implementation we did not write).
#include "mjc/protocol/crc32.h"

#include <gtest/gtest.h>
#include <zlib.h>

#include <algorithm>
#include <vector>

#include "mjc/protocol/calibration_record.h"
#include "vector_test.h"

namespace {

TEST(Crc32, MatchesZlib) {
  mjc::vt::Rng rng(701);
  for (int n = 0; n < 2000; ++n) {
    std::vector<std::uint8_t> data(static_cast<std::size_t>(rng.Next() % 300u));
    for (auto& b : data) b = static_cast<std::uint8_t>(rng.Next());
    const uLong reference =
        crc32(crc32(0L, Z_NULL, 0), data.data(), static_cast<uInt>(data.size()));
    ASSERT_EQ(mjc::protocol::Crc32(data), static_cast<std::uint32_t>(reference))
        << data.size();
  }
  // The standard check value of CRC-32/ISO-HDLC.
  const std::uint8_t check[] = {'1', '2', '3', '4', '5', '6', '7', '8', '9'};
  EXPECT_EQ(mjc::protocol::Crc32(check), 0xCBF43926u);
}

// In pieces (as the bootloader reads an image out of flash) it is the same CRC.
TEST(Crc32, InPiecesEqualsWhole) {
  mjc::vt::Rng rng(702);
  for (int n = 0; n < 200; ++n) {
    std::vector<std::uint8_t> data(static_cast<std::size_t>(rng.Next() % 3000u));
    for (auto& b : data) b = static_cast<std::uint8_t>(rng.Next());
    std::uint32_t state = mjc::protocol::kCrc32Init;
    for (std::size_t at = 0; at < data.size();) {
      const std::size_t n_piece =
          std::min<std::size_t>(data.size() - at, 1 + rng.Next() % 700u);
      state = mjc::protocol::Crc32Update(
          state, std::span<const std::uint8_t>(data).subspan(at, n_piece));
      at += n_piece;
    }
    ASSERT_EQ(mjc::protocol::Crc32Final(state), mjc::protocol::Crc32(data));
  }
}

}  // namespace
