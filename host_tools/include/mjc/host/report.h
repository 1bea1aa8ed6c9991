// Statistics and report output shared by the simulator's reproduction and the `mjc`
// trial/report commands: summary statistics, RMSE, CSV tables, gnuplot figures.
#pragma once

#include <filesystem>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace mjc::host {

struct Stats {
  int n = 0;
  double mean = 0;
  double std = 0;  // sample standard deviation (n − 1); 0 for n < 2
  double se = 0;   // standard error of the mean, std / √n
};

Stats Describe(std::span<const double> values);

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

// Runs gnuplot on `script` (written next to its outputs so it can be re-run by hand).
// What gnuplot says goes to `script`.log, removed when it succeeds. Returns false with
// a reason (gnuplot's last line, and where the rest is) when gnuplot is missing or
// fails.
bool RunGnuplot(const std::filesystem::path& script, std::string* why);

}  // namespace mjc::host
