#include "mjc/host/report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <stdexcept>

namespace mjc::host {

Stats Describe(std::span<const double> values) {
  Stats s;
  s.n = static_cast<int>(values.size());
  if (s.n == 0) return s;
  double sum = 0;
  for (double v : values) sum += v;
  s.mean = sum / s.n;
  if (s.n < 2) return s;
  double ss = 0;
  for (double v : values) ss += (v - s.mean) * (v - s.mean);
  s.std = std::sqrt(ss / (s.n - 1));
  s.se = s.std / std::sqrt(static_cast<double>(s.n));
  return s;
}

double Rmse(std::span<const double> a, std::span<const double> b) {
  if (a.size() != b.size() || a.empty()) {
    throw std::invalid_argument("Rmse: spans must have the same non-zero length");
  }
  double ss = 0;
  for (std::size_t i = 0; i < a.size(); ++i) ss += (a[i] - b[i]) * (a[i] - b[i]);
  return std::sqrt(ss / static_cast<double>(a.size()));
}

double Range(std::span<const double> values) {
  if (values.empty()) return 0;
  const auto [lo, hi] = std::minmax_element(values.begin(), values.end());
  return *hi - *lo;
}

CsvTable::CsvTable(std::vector<std::string> columns) : columns_(std::move(columns)) {}

void CsvTable::AddRow(const std::vector<std::string>& cells) {
  if (cells.size() != columns_.size()) {
    throw std::invalid_argument("CsvTable: row has " + std::to_string(cells.size()) +
                                " cells, header has " + std::to_string(columns_.size()));
  }
  rows_.push_back(cells);
}

std::string CsvTable::Number(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.9g", v);
  return text;
}

void CsvTable::Write(const std::filesystem::path& path) const {
  std::ofstream out(path);
  if (!out) throw std::runtime_error("cannot write " + path.string());
  auto line = [&out](const std::vector<std::string>& cells) {
    for (std::size_t i = 0; i < cells.size(); ++i) out << (i ? "," : "") << cells[i];
    out << '\n';
  };
  line(columns_);
  for (const auto& r : rows_) line(r);
  if (!out) throw std::runtime_error("error writing " + path.string());
}

bool RunGnuplot(const std::filesystem::path& script, std::string* why) {
  if (std::system("command -v gnuplot >/dev/null 2>&1") != 0) {
    *why = "gnuplot is not installed (apt-get install gnuplot-nox)";
    return false;
  }
  const std::string command = "cd '" + script.parent_path().string() + "' && gnuplot '" +
                              script.filename().string() + "' 2>&1";
  const int rc = std::system(command.c_str());
  if (rc != 0) {
    *why = "gnuplot failed on " + script.string() + " (exit " + std::to_string(rc) + ")";
    return false;
  }
  return true;
}

}  // namespace mjc::host
