// Power cuts during calibration updates on the simulated flash, for ./bench: every
// step of an update and 2,000 random points, and the boots that found neither the old
// nor the new record (goal 0). The sweeps are tests/unit/app/calibration_powercut_rig.h;
// the goals are asserted by tests/unit/app/calibration_store_test.cc.
#include <cstdio>

#include "calibration_powercut_rig.h"

int main() {
  using namespace mjc::calibration_powercut;
  const Sweep step = EveryStep();
  const Sweep random = RandomPoints();
  std::printf("powercut_points: %d cuts (%d at every step of an update, %d random)\n",
              step.points + random.points, step.points, random.points);
  std::printf("powercut_lost: %d boots (goal 0)\n", step.lost + random.lost);
  std::printf(
      "powercut_ecc_reads: %d boots (a page the cut left with a bad ECC, read and "
      "survived)\n",
      step.ecc_reads + random.ecc_reads);
  return 0;
}
