// Wrap-safe counter helpers against a reference computed in wide signed integers.
#include <cstdint>

#include "mjc/core/wrapping.h"
#include "vector_test.h"

namespace {

// The signed step of a 16-bit counter, computed without wrap-around arithmetic: the
// representative of (now - before) mod 65536 in [-32768, 32768).
std::int32_t ReferenceDelta16(std::int32_t now, std::int32_t before) {
  std::int32_t d = (now - before) % 65536;
  if (d < 0) d += 65536;
  return d >= 32768 ? d - 65536 : d;
}

MJC_VECTOR_TEST(Wrapping, Delta16AllStepsFromSampledStarts) {
  int mismatches = 0;
  for (std::int32_t before = 0; before < 65536; before += 4099) {
    for (std::int32_t now = 0; now < 65536; ++now) {
      const auto got = mjc::WrappingDelta(static_cast<std::uint16_t>(now),
                                          static_cast<std::uint16_t>(before));
      if (got != ReferenceDelta16(now, before)) ++mismatches;
    }
  }
  VT_EXPECT_EQ(mismatches, 0);
}

MJC_VECTOR_TEST(Wrapping, ExtendingAcrossManyWrapsLosesNothing) {
  // A 16-bit counter driven by steps up to +/-32767 in both directions: accumulating
  // WrappingDelta reconstructs the true 64-bit position after hundreds of wraps.
  mjc::vt::Rng rng(71);
  std::int64_t truth = 0;
  std::int64_t extended = 0;
  std::uint16_t last = 0;
  for (int i = 0; i < 200000; ++i) {
    const std::int64_t step = static_cast<std::int64_t>(rng.NextI32() % 32768);
    truth += step;
    const auto counter =
        static_cast<std::uint16_t>(static_cast<std::uint64_t>(truth) & 0xFFFFu);
    extended += mjc::WrappingDelta(counter, last);
    last = counter;
  }
  VT_EXPECT_EQ(extended, truth);
  VT_EXPECT_TRUE(truth > 65536 * 4 || truth < -65536 * 4);  // many wraps happened
}

MJC_VECTOR_TEST(Wrapping, AddAndSubWrapModulo) {
  VT_EXPECT_EQ(mjc::WrappingAdd<std::uint16_t>(65535u, 2u), 1u);
  VT_EXPECT_EQ(mjc::WrappingSub<std::uint16_t>(1u, 2u), 65535u);
  VT_EXPECT_EQ(mjc::WrappingAdd<std::uint32_t>(0xFFFFFFFFu, 1u), 0u);
  VT_EXPECT_EQ(mjc::WrappingDelta<std::uint32_t>(0u, 0xFFFFFFFFu), 1);
}

}  // namespace
