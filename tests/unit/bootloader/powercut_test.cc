// Power cuts during firmware updates at every erase and program operation and at
// random points, on the simulated flash and on the STM32G474's FLASH register model
// behind its driver: no cut may leave a bricked board (the rule, and the sweeps, are
// in flash_powercut_rig.h; ./bench's flash_powercut_points and flash_bricked come from
// the same sweeps, tests/bench/flash_powercut.cc).
#include <gtest/gtest.h>

#include "flash_powercut_rig.h"

namespace {

using namespace mjc::boot::test;

TEST(FlashPowerCut, SimulatedFlash) {
  const PowerCutSweep sweep = SimulatedFlashPowerCuts();
  // Every step of an update (two trials each: with and without an old image) and
  // the 1,500 random trials.
  EXPECT_GT(sweep.points, 1500 + 2 * 10);
  EXPECT_EQ(sweep.bricked, 0) << sweep.first_failure;
}

TEST(FlashPowerCut, G474FlashRegisterModel) {
  const PowerCutSweep sweep = G474FlashModelPowerCuts();
  EXPECT_GT(sweep.points, 1000 + 2 * 10);
  EXPECT_EQ(sweep.bricked, 0) << sweep.first_failure;
}

}  // namespace
