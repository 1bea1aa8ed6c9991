// The tools' wall-clock silence bounds, with and without MJC_SILENCE_S (ctest runs this
// binary twice: once with the variable at 45, as scripts/kernel-vm sets it in a slowed
// test VM, once with it unset, as in a lab).
#include <gtest/gtest.h>

#include <chrono>
#include <cstdlib>

#include "mjc/host/board_client.h"

namespace mjc::host {
namespace {

using std::chrono::milliseconds;

// Every wall-clock silence stretches to it; an exchange's own bound is kept where it is
// longer.
TEST(SilenceFromTheEnvironment, StretchesEveryWallClockSilence) {
  ASSERT_STREQ(std::getenv("MJC_SILENCE_S"), "45");
  EXPECT_EQ(DefaultSilence(), milliseconds{45000});
  EXPECT_EQ(ExchangeSilence(milliseconds{1000}), milliseconds{45000});
  EXPECT_EQ(ExchangeSilence(milliseconds{60000}), milliseconds{60000});
}

// A node silent for 10 s is gone; one silent for an exchange's own timeout does not
// answer it.
TEST(SilenceInALab, TheBoundsOfARealBoard) {
  ASSERT_EQ(std::getenv("MJC_SILENCE_S"), nullptr);
  EXPECT_EQ(DefaultSilence(), milliseconds{10000});
  EXPECT_EQ(ExchangeSilence(milliseconds{1000}), milliseconds{1000});
}

}  // namespace
}  // namespace mjc::host
