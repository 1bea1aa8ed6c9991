// The firmware's CRC-32 against zlib's crc32 (an implementation we did not write).
#include <gtest/gtest.h>
#include <zlib.h>

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

}  // namespace
