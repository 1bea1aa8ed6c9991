// The board's state and a command's outcome: the application's own enums, and the
// numbers that travel (Heartbeat, CommandResult). One definition, so the wire and the
// application cannot disagree.
#pragma once

#include <cstdint>

namespace mjc::protocol {

//   kIdle ──StartTrial──▶ kRunning ──trajectory done / Stop──▶ kIdle
//   kIdle ──StartCalibrationSweep──▶ kCalibrating ──done / Stop──▶ kIdle
//   any ──fault (same tick: bridge off)──▶ kFault ──ClearFaults (cause gone)──▶ kIdle
// Stable numbers.
enum class BoardState : std::uint8_t {
  kIdle = 0,
  kCalibrating = 1,
  kRunning = 2,
  kFault = 3
};
constexpr bool ValidEnumValue(BoardState s) { return static_cast<std::uint8_t>(s) <= 3; }

// What the board made of a command, a configuration or a calibration. Stable numbers.
enum class CommandOutcomeCode : std::uint8_t {
  kAccepted = 0,
  kRefusedNotIdle = 1,       // configuration, calibration and trials need kIdle
  kRefusedUncalibrated = 2,  // no valid backlash calibration yet
  kRefusedInvalid = 3,       // failed validation (the detail says which check)
  kRefusedFaultActive = 4,   // ClearFaults while the cause is still present
  kRefusedBusy = 5,          // the previous request is still being applied: retry
};
constexpr bool ValidEnumValue(CommandOutcomeCode c) {
  return static_cast<std::uint8_t>(c) <= 5;
}

}  // namespace mjc::protocol
