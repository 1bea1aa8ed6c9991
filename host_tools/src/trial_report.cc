#include "mjc/host/trial_report.h"

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "mjc/host/report.h"
#include "mjc/host/trial_runner.h"

namespace mjc::host {
namespace {

// windows.csv's columns, in order; ReadWindowsCsv accepts exactly this header.
const std::vector<std::string> kColumns = {
    "trial",      "amplitude_deg", "motion",        "repetition", "eta_valid",
    "eta_pct",    "loading_J",     "unloading_J",   "net_J",      "positive_J",
    "negative_J", "peak_power_W",  "peak_torque_Nm"};

std::string Joined(const std::vector<std::string>& cells) {
  std::string out;
  for (std::size_t i = 0; i < cells.size(); ++i) out += (i ? "," : "") + cells[i];
  return out;
}

}  // namespace

std::string TrialTables(const std::vector<TrialWindows>& trials, bool repeatability) {
  std::string out;
  char line[200];
  out += repeatability ? "| trial | η mean | η std |\n|---|---|---|\n"
                       : "| amplitude | loading (mJ) | unloading (mJ) | net (mJ) | η |\n"
                         "|---|---|---|---|---|\n";
  std::vector<double> all;
  int skipped = 0;
  for (std::size_t t = 0; t < trials.size(); ++t) {
    std::vector<double> eta, load, unload, net;
    for (const BoardWindow& w :
         MiddleFlexions(trials[t].windows, trials[t].repetitions)) {
      load.push_back(w.loading_J * 1e3);
      unload.push_back(w.unloading_J * 1e3);
      net.push_back(w.net_J() * 1e3);
      if (!w.eta_valid) {
        ++skipped;
        continue;
      }
      eta.push_back(w.eta_percent);
      all.push_back(w.eta_percent);
    }
    const Stats e = Describe(eta);
    if (repeatability) {
      if (e.n == 0) {
        std::snprintf(line, sizeof line, "| %zu | n/a | n/a |\n", t + 1);
      } else {
        std::snprintf(line, sizeof line, "| %zu | %.2f%% | %.3f%% |\n", t + 1, e.mean,
                      e.std);
      }
    } else {
      const Stats l = Describe(load), u = Describe(unload), n = Describe(net);
      char eta_text[32] = "n/a";
      if (e.n > 0) std::snprintf(eta_text, sizeof eta_text, "%.1f%%", e.mean);
      std::snprintf(
          line, sizeof line, "| %.0f° | %.3f ± %.3f | %.3f ± %.3f | %.3f ± %.3f | %s |\n",
          trials[t].amplitude_deg, l.mean, l.se, u.mean, u.se, n.mean, n.se, eta_text);
    }
    out += line;
  }
  if (repeatability) {
    const Stats e = Describe(all);
    if (e.n == 0) {
      std::snprintf(line, sizeof line, "| overall | n/a | n/a |\n");
    } else {
      std::snprintf(line, sizeof line, "| overall | %.2f%% | %.3f%% |\n", e.mean, e.std);
    }
    out += line;
  }
  if (skipped > 0) {
    std::snprintf(line, sizeof line,
                  "\nη leaves out %d analysed window(s) the board marked invalid.\n",
                  skipped);
    out += line;
  }
  return out;
}

bool SameAmplitude(const std::vector<TrialWindows>& trials) {
  return std::all_of(trials.begin(), trials.end(), [&](const TrialWindows& t) {
    return t.amplitude_deg == trials.front().amplitude_deg;
  });
}

void WriteWindowsCsv(const std::vector<TrialWindows>& trials,
                     const std::filesystem::path& dir) {
  CsvTable csv(kColumns);
  for (std::size_t t = 0; t < trials.size(); ++t) {
    for (const BoardWindow& w : trials[t].windows) {
      csv.AddRow({std::to_string(t + 1), CsvTable::Number(trials[t].amplitude_deg),
                  w.motion == Motion::kFlexion ? "flexion" : "extension",
                  std::to_string(w.repetition), w.eta_valid ? "1" : "0",
                  CsvTable::Number(w.eta_percent), CsvTable::Number(w.loading_J),
                  CsvTable::Number(w.unloading_J), CsvTable::Number(w.net_J()),
                  CsvTable::Number(w.positive_J), CsvTable::Number(w.negative_J),
                  CsvTable::Number(w.peak_power_W), CsvTable::Number(w.peak_torque_Nm)});
    }
  }
  csv.Write(dir / "windows.csv");
}

std::optional<std::vector<TrialWindows>> ReadWindowsCsv(const std::filesystem::path& dir,
                                                        std::string* why) {
  const std::filesystem::path path = dir / "windows.csv";
  std::ifstream in(path);
  if (!in) {
    *why = "no windows.csv in " + dir.string() + " (write one with mjc trial --out)";
    return std::nullopt;
  }
  std::string line;
  std::getline(in, line);
  if (line != Joined(kColumns)) {
    *why = path.string() + ": the header is not '" + Joined(kColumns) +
           "' (written by another version of mjc trial?)";
    return std::nullopt;
  }
  std::vector<TrialWindows> trials;
  int number = 1;
  while (std::getline(in, line)) {
    ++number;
    std::vector<std::string> cell;
    std::stringstream row(line);
    for (std::string c; std::getline(row, c, ',');) cell.push_back(c);
    try {
      if (cell.size() != kColumns.size()) throw std::invalid_argument("cells");
      if (cell[2] != "flexion" && cell[2] != "extension")
        throw std::invalid_argument("motion");
      if (cell[4] != "0" && cell[4] != "1") throw std::invalid_argument("eta_valid");
      const auto t = static_cast<std::size_t>(std::stoul(cell[0]));
      const unsigned long repetition = std::stoul(cell[3]);
      if (t == 0 || t > 10000 || repetition > 0xFFFE) throw std::out_of_range("range");
      if (trials.size() < t) trials.resize(t);
      TrialWindows& tw = trials[t - 1];
      tw.amplitude_deg = std::stod(cell[1]);
      BoardWindow w;
      w.motion = cell[2] == "flexion" ? Motion::kFlexion : Motion::kExtension;
      w.repetition = static_cast<std::uint16_t>(repetition);
      w.eta_valid = cell[4] == "1";
      w.eta_percent = std::stod(cell[5]);
      w.loading_J = std::stod(cell[6]);
      w.unloading_J = std::stod(cell[7]);
      w.positive_J = std::stod(cell[9]);
      w.negative_J = std::stod(cell[10]);
      w.peak_power_W = std::stod(cell[11]);
      w.peak_torque_Nm = std::stod(cell[12]);
      tw.repetitions =
          std::max(tw.repetitions, static_cast<std::uint16_t>(w.repetition + 1));
      tw.windows.push_back(w);
    } catch (const std::exception&) {
      *why = path.string() + ": line " + std::to_string(number) + " is malformed";
      return std::nullopt;
    }
  }
  if (trials.empty()) {
    *why = path.string() + " holds no windows";
    return std::nullopt;
  }
  return trials;
}

bool PlotTrials(const std::filesystem::path& dir, bool repeatability, std::string* why) {
  // Columns: 1 trial, 2 amplitude_deg, 3 motion, 5 eta_valid, 6 eta_pct.
  const auto script = dir / "eta.gp";
  WriteFile(script, std::string("set terminal pngcairo size 900,600\n"
                                "set output 'eta.png'\n"
                                "set datafile separator ','\nset grid\n") +
                        (repeatability ? "set xlabel 'trial'\n"
                                       : "set xlabel 'amplitude (°)'\n") +
                        "set ylabel 'energy loss η (%)'\n"
                        "plot 'windows.csv' every ::1 using " +
                        (repeatability ? "1" : "2") +
                        ":(strcol(3) eq 'flexion' && $5 == 1 ? $6 : 1/0) "
                        "with points pt 7 title 'flexion windows'\n");
  return RunGnuplot(script, why);
}

}  // namespace mjc::host
