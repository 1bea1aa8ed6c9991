// The mjc subcommands. Each Add* registers its subcommand (options and a callback) on
// the CLI11 app; the callbacks return the process exit status through `status`.
#pragma once

#include <CLI/CLI.hpp>

namespace mjc::cli {

void AddSim(CLI::App& app, int* status);
void AddLog(CLI::App& app, int* status);
void AddCal(CLI::App& app, int* status);
void AddCalibrate(CLI::App& app, int* status);
void AddBusload(CLI::App& app, int* status);
void AddTrial(CLI::App& app, int* status);
void AddReport(CLI::App& app, int* status);
void AddMonitor(CLI::App& app, int* status);

}  // namespace mjc::cli
