// MulShiftRound against a 128-bit integer reference (host only: Cortex-M4 compilers
// have no __int128, which is why MulShiftRound exists).
#include <gtest/gtest.h>

#include <cstdint>
#include <limits>

#include "mjc/core/fixed.h"
#include "vector_test.h"

namespace {

std::int64_t Reference(std::int64_t a, std::int32_t m, int shift) {
  const __int128 p = static_cast<__int128>(a) * m;
  const __int128 half = static_cast<__int128>(1) << (shift - 1);
  return static_cast<std::int64_t>((p + half) >> shift);  // floor(x + 1/2)
}

TEST(MulShiftRound, MatchesInt128ReferenceOverWholeRange) {
  mjc::vt::Rng rng(91);
  const std::int64_t edges[] = {std::numeric_limits<std::int64_t>::min(),
                                std::numeric_limits<std::int64_t>::max(),
                                0,
                                1,
                                -1,
                                (std::int64_t{1} << 32) - 1,
                                -(std::int64_t{1} << 32),
                                (std::int64_t{1} << 31),
                                -(std::int64_t{1} << 31) - 1};
  const std::int32_t medges[] = {std::numeric_limits<std::int32_t>::min(),
                                 std::numeric_limits<std::int32_t>::max(),
                                 0,
                                 1,
                                 -1,
                                 3};
  for (int shift = 32; shift <= 62; ++shift) {
    for (auto a : edges) {
      for (auto m : medges) {
        ASSERT_EQ(mjc::MulShiftRound(a, m, shift), Reference(a, m, shift))
            << a << " * " << m << " >> " << shift;
      }
    }
    for (int i = 0; i < 20000; ++i) {
      const std::int64_t a = rng.NextI64() >> (rng.Next() % 40u);
      const std::int32_t m = rng.NextI32() >> (rng.Next() % 31u);
      ASSERT_EQ(mjc::MulShiftRound(a, m, shift), Reference(a, m, shift))
          << a << " * " << m << " >> " << shift;
    }
  }
}

TEST(MulShiftRound, UnsignedMultiplierMatchesInt128Reference) {
  mjc::vt::Rng rng(92);
  for (int shift = 32; shift <= 62; ++shift) {
    for (int i = 0; i < 20000; ++i) {
      const std::int64_t a = rng.NextI64() >> (rng.Next() % 40u);
      const auto m = static_cast<std::int32_t>(
          static_cast<std::uint32_t>(rng.NextI32()) >> (1 + rng.Next() % 31u));
      ASSERT_EQ(mjc::MulShiftRoundUnsigned(a, static_cast<std::uint32_t>(m), shift),
                Reference(a, m, shift))
          << a << " * " << m << " >> " << shift;
    }
    const std::int32_t kMax = std::numeric_limits<std::int32_t>::max();
    for (const std::int64_t a :
         {std::numeric_limits<std::int64_t>::min(),
          std::numeric_limits<std::int64_t>::max(), std::int64_t{-1}}) {
      ASSERT_EQ(mjc::MulShiftRoundUnsigned(a, static_cast<std::uint32_t>(kMax), shift),
                Reference(a, kMax, shift));
    }
  }
}

TEST(MulShiftRound, TiesRoundTowardPlusInfinity) {
  EXPECT_EQ(mjc::MulShiftRound(std::int64_t{1} << 31, 1, 32), 1);     // 0.5 -> 1
  EXPECT_EQ(mjc::MulShiftRound(-(std::int64_t{1} << 31), 1, 32), 0);  // -0.5 -> 0
  EXPECT_EQ(mjc::MulShiftRound(3LL << 32, 1, 33), 2);                 // 1.5 -> 2
  EXPECT_EQ(mjc::MulShiftRound(-(3LL << 32), 1, 33), -1);             // -1.5 -> -1
}

}  // namespace
