#include "mjc/host/trial_report.h"

#include <cstdio>
#include <fstream>
#include <sstream>

#include "mjc/host/report.h"
#include "mjc/host/trial_runner.h"

namespace mjc::host {

std::string TrialTables(const std::vector<TrialWindows>& trials,
                        std::uint16_t repetitions, bool repeatability) {
  std::string out;
  char line[200];
  out += repeatability ? "| trial | η mean | η std |\n|---|---|---|\n"
                       : "| amplitude | loading (mJ) | unloading (mJ) | net (mJ) | η |\n"
                         "|---|---|---|---|---|\n";
  std::vector<double> all;
  for (std::size_t t = 0; t < trials.size(); ++t) {
    std::vector<double> eta, load, unload, net;
    for (const BoardWindow& w : MiddleFlexions(trials[t].windows, repetitions)) {
      eta.push_back(w.eta_percent);
      load.push_back(w.loading_J * 1e3);
      unload.push_back(w.unloading_J * 1e3);
      net.push_back(w.net_J() * 1e3);
      all.push_back(w.eta_percent);
    }
    const Stats e = Describe(eta);
    if (repeatability) {
      std::snprintf(line, sizeof line, "| %zu | %.2f%% | %.3f%% |\n", t + 1, e.mean,
                    e.std);
    } else {
      const Stats l = Describe(load), u = Describe(unload), n = Describe(net);
      std::snprintf(line, sizeof line,
                    "| %.0f° | %.3f ± %.3f | %.3f ± %.3f | %.3f ± %.3f | %.1f%% |\n",
                    trials[t].amplitude_deg, l.mean, l.se, u.mean, u.se, n.mean, n.se,
                    e.mean);
    }
    out += line;
  }
  if (repeatability) {
    const Stats e = Describe(all);
    std::snprintf(line, sizeof line, "| overall | %.2f%% | %.3f%% |\n", e.mean, e.std);
    out += line;
  }
  return out;
}

void WriteWindowsCsv(const std::vector<TrialWindows>& trials,
                     const std::filesystem::path& dir) {
  CsvTable csv({"trial", "amplitude_deg", "motion", "repetition", "eta_pct", "loading_J",
                "unloading_J", "net_J", "peak_power_W", "peak_torque_Nm"});
  for (std::size_t t = 0; t < trials.size(); ++t) {
    for (const BoardWindow& w : trials[t].windows) {
      csv.AddRow({std::to_string(t + 1), CsvTable::Number(trials[t].amplitude_deg),
                  w.motion == Motion::kFlexion ? "flexion" : "extension",
                  std::to_string(w.repetition), CsvTable::Number(w.eta_percent),
                  CsvTable::Number(w.loading_J), CsvTable::Number(w.unloading_J),
                  CsvTable::Number(w.net_J()), CsvTable::Number(w.peak_power_W),
                  CsvTable::Number(w.peak_torque_Nm)});
    }
  }
  csv.Write(dir / "windows.csv");
}

std::optional<std::vector<TrialWindows>> ReadWindowsCsv(const std::filesystem::path& dir,
                                                        std::string* why) {
  std::ifstream in(dir / "windows.csv");
  if (!in) {
    *why = "no windows.csv in " + dir.string() + " (write one with mjc trial --out)";
    return std::nullopt;
  }
  std::string line;
  std::getline(in, line);  // header
  std::vector<TrialWindows> trials;
  int number = 1;
  while (std::getline(in, line)) {
    ++number;
    std::stringstream row(line);
    std::string cell[10];
    for (auto& c : cell) std::getline(row, c, ',');
    try {
      const auto t = static_cast<std::size_t>(std::stoul(cell[0]));
      if (t == 0 || t > 10000) throw std::out_of_range("trial");
      if (trials.size() < t) trials.resize(t);
      TrialWindows& tw = trials[t - 1];
      tw.amplitude_deg = std::stod(cell[1]);
      BoardWindow w;
      w.motion = cell[2] == "flexion" ? Motion::kFlexion : Motion::kExtension;
      w.repetition = static_cast<std::uint16_t>(std::stoul(cell[3]));
      w.eta_percent = std::stod(cell[4]);
      w.eta_valid = true;
      w.loading_J = std::stod(cell[5]);
      w.unloading_J = std::stod(cell[6]);
      w.peak_power_W = std::stod(cell[8]);
      w.peak_torque_Nm = std::stod(cell[9]);
      tw.windows.push_back(w);
    } catch (const std::exception&) {
      *why = (dir / "windows.csv").string() + ": line " + std::to_string(number) +
             " is malformed";
      return std::nullopt;
    }
  }
  if (trials.empty()) {
    *why = (dir / "windows.csv").string() + " holds no windows";
    return std::nullopt;
  }
  return trials;
}

bool PlotTrials(const std::filesystem::path& dir, std::string* why) {
  const auto script = dir / "eta.gp";
  std::ofstream(script)
      << "set terminal pngcairo size 900,600\nset output 'eta.png'\n"
         "set datafile separator ','\nset grid\nset xlabel 'trial'\n"
         "set ylabel 'energy loss η (%)'\n"
         "plot 'windows.csv' every ::1 using 1:(strcol(3) eq 'flexion' ? $5 : 1/0) "
         "with points pt 7 title 'flexion windows'\n";
  return RunGnuplot(script, why);
}

}  // namespace mjc::host
