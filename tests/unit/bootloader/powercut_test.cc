// Power cuts during firmware updates at every erase and program operation and at
// random points, on the simulated flash and on the STM32G474's FLASH register model
// behind its driver: no cut may leave a bricked board (the rule, and the sweeps, are
// in flash_powercut_rig.h; ./bench's flash_powercut_points and flash_bricked come from
// the same sweeps, tests/bench/flash_powercut.cc). Both flashes leave what a cut
// interrupted with an ECC error, and the sweeps must have made the board read such
// double words often, or they prove nothing about surviving them. Most cuts fall in an
// image page that the next update erases before anything reads it; the ones the board
// reads are those in the header page (its erase at Begin, its program at Commit) and
// in the image while the bootloader checks it: 158 and 238 of these sweeps.
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
  EXPECT_GE(sweep.ecc_reads, 50);
}

TEST(FlashPowerCut, G474FlashRegisterModel) {
  const PowerCutSweep sweep = G474FlashModelPowerCuts();
  EXPECT_GT(sweep.points, 1000 + 2 * 10);
  EXPECT_EQ(sweep.bricked, 0) << sweep.first_failure;
  EXPECT_GE(sweep.ecc_reads, 50);
}

}  // namespace
