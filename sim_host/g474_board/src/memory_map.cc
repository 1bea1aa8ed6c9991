// What the image's linker script gives the board's code on the chip, for its host
// build: the calibration pages' address (the script's CAL region, read from
// linker/stm32g474.ld by the build, so the two cannot differ).
#include "board.h"

namespace mjc::board {

std::uint32_t CalibrationAddress() { return MJC_G474_CALIBRATION_ADDRESS; }

}  // namespace mjc::board
