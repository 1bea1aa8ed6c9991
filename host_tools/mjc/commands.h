// The mjc subcommands. Each Add* registers its subcommand (options and a callback) on
// the CLI11 app; the callbacks return the process exit status through `status`.
#pragma once

#include <CLI/CLI.hpp>

namespace mjc::cli {

// Slowest trial or sweep the board accepts at its 10 kHz tick: a window (half a cycle)
// must fit the 16-bit tick offsets of its WindowTicks frame (65,535 ticks, 76.3 mHz);
// slower ones are refused with kDetailWindowTooLong.
inline constexpr double kMinFrequencyHz = 0.08;
inline constexpr double kMaxFrequencyHz = 5.0;

void AddSim(CLI::App& app, int* status);
void AddLog(CLI::App& app, int* status);
void AddCal(CLI::App& app, int* status);
void AddCalibrate(CLI::App& app, int* status);
void AddBusload(CLI::App& app, int* status);
void AddTrial(CLI::App& app, int* status);
void AddReport(CLI::App& app, int* status);
void AddMonitor(CLI::App& app, int* status);

}  // namespace mjc::cli
