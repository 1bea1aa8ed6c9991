// Statistics and report output shared by the simulator's reproduction and the `mjc`
// trial/report commands: summary statistics, RMSE, CSV tables, gnuplot figures.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "mjc/core/interface_energy.h"

namespace mjc::host {

struct Stats {
  int n = 0;
  double mean = 0;
  double std = 0;  // sample standard deviation (n − 1); 0 for n < 2
  double se = 0;   // standard error of the mean, std / √n
};

Stats Describe(std::span<const double> values);

// The repetitions the paper analyses of a trial of `repetitions`: the middle three.
constexpr RepetitionRange AnalysedRepetitions(std::uint16_t repetitions) {
  return MiddleRepetitions(repetitions, 3);
}
// A window the paper analyses: a flexion of an analysed repetition.
constexpr bool IsAnalysedFlexion(Motion motion, std::uint16_t repetition,
                                 std::uint16_t repetitions) {
  return motion == Motion::kFlexion &&
         AnalysedRepetitions(repetitions).Contains(repetition);
}
// The analysed flexions among a trial's windows, in their order: of the board's window
// summaries as the host receives them, or of the simulator's windows against the
// plant's truth (any Window with `motion` and `repetition`, counted from 0).
template <class Window>
std::vector<const Window*> AnalysedFlexions(const std::vector<Window>& windows,
                                            std::uint16_t repetitions) {
  std::vector<const Window*> out;
  for (const Window& w : windows) {
    if (IsAnalysedFlexion(w.motion, w.repetition, repetitions)) out.push_back(&w);
  }
  return out;
}

// √(mean((a − b)²)); the spans must be the same non-zero length.
double Rmse(std::span<const double> a, std::span<const double> b);

// max − min of the values (0 for an empty span).
double Range(std::span<const double> values);

// A CSV table written row by row: a header line, then rows of numbers or strings.
// Numbers are written with enough digits to round-trip (%.9g).
class CsvTable {
 public:
  explicit CsvTable(std::vector<std::string> columns);
  void AddRow(const std::vector<std::string>& cells);
  static std::string Number(double v);
  // Writes the table; throws std::runtime_error naming the path on failure.
  void Write(const std::filesystem::path& path) const;

 private:
  std::vector<std::string> columns_;
  std::vector<std::vector<std::string>> rows_;
};

// Writes `text` as the whole of the file at `path` (created or replaced). Throws
// std::runtime_error naming the path and the system's reason when it cannot be opened,
// written or closed, so a full disk or a missing folder is never a silent loss.
void WriteFile(const std::filesystem::path& path, std::string_view text);

// The whole of the file at `path`; nullopt when it cannot be opened or read.
std::optional<std::string> ReadFileText(const std::filesystem::path& path);

// WriteFile for a file that is rewritten while a run goes on (run.json): the text goes
// to `path`.tmp, which then replaces `path` in one rename, so a reader — or whoever
// finds the folder after this process was killed mid-write — sees the old text or the
// new one, whole, never a cut one. Throws as WriteFile.
void ReplaceFile(const std::filesystem::path& path, std::string_view text);

// A file written a record at a time, as the records arrive (windows.csv, sweep.csv):
// each Append goes to the kernel at once with write(2), no buffer in this process, so
// the process's death (SIGKILL, a crash, an OOM kill) loses nothing already appended.
// (The kernel writes it to disk in its own time: a power cut may lose its last
// seconds, the process's end never.)
class AppendFile {
 public:
  // Creates `path` (truncating a file of that name: the run's folder was prepared for
  // it); throws std::runtime_error naming the path and the system's reason.
  explicit AppendFile(std::filesystem::path path);
  ~AppendFile();
  AppendFile(const AppendFile&) = delete;
  AppendFile& operator=(const AppendFile&) = delete;
  // Appends `text` whole (retrying short writes); throws std::runtime_error naming the
  // path when it cannot (a full disk), so a lost record is never silent.
  void Append(std::string_view text);
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
  int fd_ = -1;
};

// Runs gnuplot on `script` (written next to its outputs so it can be re-run by hand).
// What gnuplot says goes to `script`.log, removed when it succeeds. Returns false with
// a reason (gnuplot's last line, and where the rest is) when gnuplot is missing or
// fails.
bool RunGnuplot(const std::filesystem::path& script, std::string* why);

}  // namespace mjc::host
