#include "mjc/host/report.h"

#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
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
  std::string text;
  auto line = [&text](const std::vector<std::string>& cells) {
    for (std::size_t i = 0; i < cells.size(); ++i) text += (i ? "," : "") + cells[i];
    text += '\n';
  };
  line(columns_);
  for (const auto& r : rows_) line(r);
  WriteFile(path, text);
}

void WriteFile(const std::filesystem::path& path, std::string_view text) {
  const auto fail = [&path](const char* what) {
    throw std::runtime_error(std::string(what) + " " + path.string() + ": " +
                             std::strerror(errno));
  };
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (f == nullptr) fail("cannot write");
  if (std::fwrite(text.data(), 1, text.size(), f) != text.size()) {
    const int error = errno;
    std::fclose(f);
    errno = error;
    fail("error writing");
  }
  if (std::fclose(f) != 0) fail("error writing");  // buffered data meets the disk here
}

std::optional<std::string> ReadFileText(const std::filesystem::path& path) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (f == nullptr) return std::nullopt;
  std::string text;
  char buffer[8192];
  for (std::size_t n; (n = std::fread(buffer, 1, sizeof buffer, f)) > 0;) {
    text.append(buffer, n);
  }
  const bool failed = std::ferror(f) != 0;
  std::fclose(f);
  if (failed) return std::nullopt;
  return text;
}

void ReplaceFile(const std::filesystem::path& path, std::string_view text) {
  std::filesystem::path temporary = path;
  temporary += ".tmp";
  WriteFile(temporary, text);
  std::error_code error;
  std::filesystem::rename(temporary, path, error);
  if (error) {
    throw std::runtime_error("cannot replace " + path.string() + ": " + error.message());
  }
}

AppendFile::AppendFile(std::filesystem::path path) : path_(std::move(path)) {
  fd_ = ::open(path_.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_APPEND | O_CLOEXEC, 0666);
  if (fd_ < 0) {
    throw std::runtime_error("cannot write " + path_.string() + ": " +
                             std::strerror(errno));
  }
}

AppendFile::~AppendFile() {
  if (fd_ >= 0) ::close(fd_);
}

void AppendFile::Append(std::string_view text) {
  while (!text.empty()) {
    const ssize_t n = ::write(fd_, text.data(), text.size());
    if (n < 0 && errno == EINTR)
      continue;  // a signal (Ctrl-C) before anything was written
    if (n <= 0) {
      throw std::runtime_error("error writing " + path_.string() + ": " +
                               (n < 0 ? std::strerror(errno) : "nothing written"));
    }
    text.remove_prefix(static_cast<std::size_t>(n));
  }
}

bool RunGnuplot(const std::filesystem::path& script, std::string* why) {
  if (std::system("command -v gnuplot >/dev/null 2>&1") != 0) {
    *why = "gnuplot is not installed (apt-get install gnuplot-nox)";
    return false;
  }
  // Everything gnuplot says (its warnings too: a font it substitutes, an empty range)
  // goes to a log beside the script, shown only when it fails: a figure that was drawn
  // needs no chatter on the terminal.
  std::filesystem::path log = script;
  log += ".log";
  const std::string command = "cd '" + script.parent_path().string() + "' && gnuplot '" +
                              script.filename().string() + "' >'" +
                              log.filename().string() + "' 2>&1";
  const int status = std::system(command.c_str());
  if (status == -1 || !WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    std::string said;
    std::ifstream in(log);
    for (std::string line; std::getline(in, line);) {
      if (line.find_first_not_of(" \t^") != std::string::npos) said = line;
    }
    *why = "gnuplot failed on " + script.string() +
           (status != -1 && WIFEXITED(status)
                ? " (exit " + std::to_string(WEXITSTATUS(status)) + ")"
                : std::string(" (did not run to completion)")) +
           (said.empty() ? "" : ": " + said) + "; all it said is in " + log.string();
    return false;
  }
  std::error_code ignored;
  std::filesystem::remove(log, ignored);
  return true;
}

}  // namespace mjc::host
