// Power cuts during firmware updates, the way the calibration store's sweeps cut them:
// at every erase and program operation of an update and at random points (with 1-3
// cuts in a row, each in the update that recovers from the one before), on two flashes
// — the simulated flash (hal::SimFlash), and the STM32G474's FLASH register model
// (sim_host/g474's VirtualChip) driven by the real driver (Stm32g4Flash). An
// interrupted erase leaves its page random, an interrupted program a random mix of the
// double-word's old and new bits, and both leave the double words they cut with an ECC
// that does not match (a read of one fails: an NMI on the chip, taken by the image's
// NMI handler as the G474 images install it). Shared by
// tests/unit/bootloader/powercut_test.cc (the goal, asserted) and
// tests/bench/flash_powercut.cc (./bench's flash_powercut_points and flash_bricked).
//
// After each cut the board powers up again (its RAM random) and the bootloader decides.
// The rule: it hands over only to the old image or the new one, byte for byte whole as
// the host's file has it (compared here, independently of the bootloader's own check),
// or it stays in the bootloader — and then takes the image again, after which the new
// image boots. Nothing outside the application region may change, and after every cut
// a header that checks out stands only in front of the whole image it names (the commit
// discipline, checked in the flash itself). Any break of these rules, and any rule of
// the reference manual the driver breaks on the register model, counts as a bricked
// board.
#pragma once

#include <string>

namespace mjc::boot::test {

struct PowerCutSweep {
  int points = 0;   // trials (each one to three cuts)
  int bricked = 0;  // trials that broke the rule (goal 0)
  // Trials in which the board (its bootloader at power-up or during the next update)
  // read a double word the cut had left with an ECC error: the sweep's proof that
  // the images survive such reads (goal: far above zero).
  int ecc_reads = 0;
  std::string first_failure;  // where and why the first one broke it; empty if none
};

// Every operation of an update of a 5,000-byte image (one cut), onto erased flash and
// over an old image, then 1,500 random trials (images up to 12,000 bytes): about a
// minute of one core.
PowerCutSweep SimulatedFlashPowerCuts();
// The same on the G474 FLASH register model behind Stm32g4Flash: a 1,400-byte image,
// 1,000 random trials (images up to 3,000 bytes).
PowerCutSweep G474FlashModelPowerCuts();

}  // namespace mjc::boot::test
