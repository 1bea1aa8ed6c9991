// The main loop's consistent copy of what the tick leaves (mjc/app/tick_count.h). The
// tick interrupting a copy is stood for by copy functions that run the "tick" part-way
// through themselves, as the interrupt would. Runs on the host and on the Cortex-M4.
#include <cstdint>

#include "mjc/app/tick_count.h"
#include "vector_test.h"

namespace {

using mjc::app::TickCount;

MJC_VECTOR_TEST(TickCount, CountsTheTicksThatRanToTheirEnd) {
  TickCount count;
  VT_EXPECT_EQ(count.ticks(), 0u);
  for (int i = 0; i < 5; ++i) count.ISR_Advance();
  VT_EXPECT_EQ(count.ticks(), 5u);
}

MJC_VECTOR_TEST(TickCount, ACopyATickInterruptedIsTakenAgain) {
  TickCount count;
  int copies = 0;
  VT_EXPECT_EQ(count.Read([&] { return ++copies; }), 1);  // undisturbed: one copy
  copies = 0;
  const int kept = count.Read([&] {
    ++copies;
    if (copies <= 2) count.ISR_Advance();  // a tick during the first two copies
    return copies;
  });
  VT_EXPECT_EQ(kept, 3);
  VT_EXPECT_EQ(copies, 3);
  VT_EXPECT_EQ(count.ticks(), 2u);
}

// A 64-bit value is two words on the Cortex-M4: a copy that reads the low word, is
// interrupted by a tick writing a new value, then reads the high word holds half of
// each. The copy Read returns is never such a mix.
MJC_VECTOR_TEST(TickCount, NeverReturnsATornValue) {
  TickCount count;
  std::uint32_t words[2] = {0xFFFF'FFFFu, 0x0000'0000u};  // 0x00000000FFFFFFFF
  const auto tick = [&](std::uint64_t value) {
    words[0] = static_cast<std::uint32_t>(value);
    words[1] = static_cast<std::uint32_t>(value >> 32);
    count.ISR_Advance();
  };
  int interrupt_after_low = 1;  // the first copy is interrupted half-way
  const std::uint64_t copy = count.Read([&] {
    const std::uint32_t low = words[0];
    if (interrupt_after_low-- > 0) tick(0x0000'0001'0000'0000u);
    const std::uint32_t high = words[1];
    return (std::uint64_t{high} << 32) | low;
  });
  // The torn copy would be 0x00000001FFFFFFFF, neither the old value nor the new one.
  VT_EXPECT_TRUE(copy == 0x0000'0001'0000'0000u);
  VT_EXPECT_EQ(count.ticks(), 1u);
}

}  // namespace
