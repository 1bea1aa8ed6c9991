// The tables of a trial run (mjc trial prints them; mjc report re-renders them from the
// windows.csv a run wrote): the middle three flexions of each trial.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "mjc/host/board_client.h"
#include "mjc/host/report.h"

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

// windows.csv as the windows arrive: the note and the header when it is created, then
// each window's row the moment it is appended, straight to the kernel (AppendFile), so a
// host that dies mid-run loses at most the window it was handling. The same file as
// WriteWindowsCsv's.
class WindowsCsvWriter {
 public:
  // Creates dir/windows.csv; throws std::runtime_error naming it when it cannot.
  explicit WindowsCsvWriter(const std::filesystem::path& dir);
  // The window `w` of trial `trial` (counted from 0) of `repetitions` at
  // `amplitude_deg`; throws std::runtime_error naming the file when it cannot be written.
  void Append(std::size_t trial, double amplitude_deg, std::uint16_t repetitions,
              const BoardWindow& w);
  std::size_t rows() const { return rows_; }
  const std::filesystem::path& path() const { return file_.path(); }

 private:
  AppendFile file_;
  std::size_t rows_ = 0;
};

// Reads a windows.csv back, of any version (*version, when given, says which): the
// windows' repetitions counted from 0 again, as the board counts them. A version 1
// file's trials take their largest repetition + 1 as their repetitions. Strict: nullopt
// with the reason, naming the line and the column, when it is missing or when a cell is
// not what the board can have sent — not a finite decimal number, outside what its
// frame carries (energies, power and torque ±128, η ±32768 %), a work of the wrong sign
// (positive_J < 0, negative_J > 0), a net_J other than loading_J + unloading_J, a valid
// η above 100 % or from a loading energy ≤ 0, an analysed flag the window contradicts —
// or when rows contradict each other: a window twice, a trial's amplitude or
// repetitions changing between its rows, a trial without windows before one with. A
// last row without its newline (the writer died in the middle of it) is left out and
// *cut_last set.
std::optional<std::vector<TrialWindows>> ReadWindowsCsv(const std::filesystem::path& dir,
                                                        std::string* why,
                                                        int* version = nullptr,
                                                        bool* cut_last = nullptr);

// The same from the text of a windows.csv; `source` names it in messages.
std::optional<std::vector<TrialWindows>> ParseWindowsCsv(const std::string& text,
                                                         const std::string& source,
                                                         std::string* why,
                                                         int* version = nullptr,
                                                         bool* cut_last = nullptr);

// eta.png in `dir` (gnuplot) from its `data` (a version 2 windows.csv): η of every valid
// flexion window against the trial number (repeatability) or the amplitude, the analysed
// flexions filled, the others open, under `title`. False with the reason when gnuplot
// fails; throws std::runtime_error when its script cannot be written.
bool PlotTrials(const std::filesystem::path& dir, bool repeatability,
                const std::string& title, std::string* why,
                const std::string& data = "windows.csv");

}  // namespace mjc::host
