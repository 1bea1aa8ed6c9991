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
  std::uint16_t repetitions = 0;     // of the trial (its middle three are analysed)
  std::vector<BoardWindow> windows;  // all of the trial's windows
};

// Markdown: η per trial (repeatability) or work per amplitude (amplitude protocol), of
// each trial's middle three flexions. Windows the board marked η-invalid count in the
// work figures but not in η's; a closing line says how many were left out.
std::string TrialTables(const std::vector<TrialWindows>& trials, bool repeatability);

// Markdown: the attachment's fit (k_i, b_i, τ_0, residual RMS) per trial, the mean over
// its analysed flexions whose fit the board could solve.
std::string AttachmentTable(const std::vector<TrialWindows>& trials);

// True when every trial ran at the same amplitude (a repeatability run, or an amplitude
// run of one amplitude).
bool SameAmplitude(const std::vector<TrialWindows>& trials);

// Writes windows.csv (every window) into `dir`, version 3: a note line, the header,
// then a row a window with its trial and repetition counted from 1, whether the
// tables analyse it, and the attachment's fit; throws std::runtime_error naming the file
// when it cannot be written.
void WriteWindowsCsv(const std::vector<TrialWindows>& trials,
                     const std::filesystem::path& dir);

// Reads a windows.csv back, of any version (*version, when given, says which): the
// windows' repetitions counted from 0 again, as the board counts them. A version 1
// file's trials take their largest repetition + 1 as their repetitions. nullopt with
// the reason when it is missing or malformed.
std::optional<std::vector<TrialWindows>> ReadWindowsCsv(const std::filesystem::path& dir,
                                                        std::string* why,
                                                        int* version = nullptr);

// eta.png in `dir` (gnuplot) from its `data` (a version 2 windows.csv): η of every valid
// flexion window against the trial number (repeatability) or the amplitude, the analysed
// flexions filled, the others open, under `title`. False with the reason when gnuplot
// fails; throws std::runtime_error when its script cannot be written.
bool PlotTrials(const std::filesystem::path& dir, bool repeatability,
                const std::string& title, std::string* why,
                const std::string& data = "windows.csv");

}  // namespace mjc::host
