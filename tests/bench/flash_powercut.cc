// Power cuts in the bootloader's flash writes, for ./bench: firmware updates cut at
// every erase and program and at random points, on the simulated flash and on the
// G474 FLASH register model behind its driver (tests/unit/bootloader/
// flash_powercut_rig.h: the rule a bricked board breaks), and the identity record's
// saves cut at every step and at random points (identity_powercut_rig.h). The goals
// are asserted by powercut_test.cc and identity_store_test.cc beside the rigs. Every
// flash here leaves what a cut interrupted with an ECC error (RM0440 §5.3);
// ecc_corrupt_reads counts the cut points whose damage the board read afterwards,
// over these sweeps and the calibration store's (tests/unit/app/
// calibration_powercut_rig.h, whose own figures tests/bench/calibration_powercut.cc
// prints).
#include <cstdio>

#include "calibration_powercut_rig.h"
#include "flash_powercut_rig.h"
#include "identity_powercut_rig.h"

int main() {
  using namespace mjc::boot::test;
  const IdentityPowerCutSweep identity = IdentityPowerCuts();
  std::printf(
      "identity_powercut_points: %d cuts (every step of a save and 2,000 random)\n",
      identity.points);
  std::printf("identity_powercut_lost: %d boots (goal 0)\n", identity.lost);
  const mjc::calibration_powercut::Sweep calibration_step =
      mjc::calibration_powercut::EveryStep();
  const mjc::calibration_powercut::Sweep calibration_random =
      mjc::calibration_powercut::RandomPoints();

  const PowerCutSweep sim = SimulatedFlashPowerCuts();
  const PowerCutSweep chip = G474FlashModelPowerCuts();
  for (const auto* s : {&sim, &chip}) {
    if (!s->first_failure.empty())
      std::fprintf(stderr, "flash_powercut: %s\n", s->first_failure.c_str());
  }
  std::printf(
      "flash_powercut_points: %d trials (simulated flash %d, G474 FLASH model %d)\n",
      sim.points + chip.points, sim.points, chip.points);
  std::printf("flash_bricked: %d boards (goal 0)\n", sim.bricked + chip.bricked);
  const int calibration_ecc = calibration_step.ecc_reads + calibration_random.ecc_reads;
  const int total_points = sim.points + chip.points + identity.points +
                           calibration_step.points + calibration_random.points;
  std::printf(
      "ecc_corrupt_reads: %d of %d cut points (damage left with a bad ECC and read by "
      "the board afterwards: updates on the simulated flash %d, on the G474 FLASH model "
      "%d; identity saves %d; calibration saves %d)\n",
      sim.ecc_reads + chip.ecc_reads + identity.ecc_reads + calibration_ecc, total_points,
      sim.ecc_reads, chip.ecc_reads, identity.ecc_reads, calibration_ecc);
  return 0;
}
