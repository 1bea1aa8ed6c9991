// The tables of a trial run (mjc trial prints them; mjc report re-renders them from the
// windows.csv a run wrote): the middle three flexions of each trial.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "mjc/host/board_client.h"

namespace mjc::host {

struct TrialWindows {
  double amplitude_deg = 0;
  std::vector<BoardWindow> windows;  // all of the trial's windows
};

// Markdown: η per trial (repeatability) or work per amplitude (amplitude protocol).
std::string TrialTables(const std::vector<TrialWindows>& trials,
                        std::uint16_t repetitions, bool repeatability);

// Writes windows.csv (every window) into `dir`.
void WriteWindowsCsv(const std::vector<TrialWindows>& trials,
                     const std::filesystem::path& dir);

// Reads a windows.csv back; nullopt with the reason when it is missing or malformed.
std::optional<std::vector<TrialWindows>> ReadWindowsCsv(const std::filesystem::path& dir,
                                                        std::string* why);

// eta.png in `dir` (gnuplot); false with the reason when gnuplot fails.
bool PlotTrials(const std::filesystem::path& dir, std::string* why);

}  // namespace mjc::host
