// What the image's linker script gives the board's code on the chip, for its host
// build: the calibration pages' address (the script's CAL region, read from
// linker/stm32g474.ld by the build, so the two cannot differ), and the block shared with
// the bootloader, in memory that outlives the virtual chip's resets as the chip's
// HANDOFF region outlives its own (the process's; zero at power-on here, where the
// chip's RAM is random: the records' magics and CRCs tell either from a valid one).
#include "board.h"

namespace mjc::board {
namespace {
boot::BootHandoff g_handoff{};
}  // namespace

std::uint32_t CalibrationAddress() { return MJC_G474_CALIBRATION_ADDRESS; }

volatile boot::BootHandoff& Handoff() { return g_handoff; }

}  // namespace mjc::board
