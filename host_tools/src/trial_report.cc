#include "mjc/host/trial_report.h"

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "mjc/host/report.h"
#include "mjc/host/trial_runner.h"

namespace mjc::host {
namespace {

// windows.csv's columns, in order: version 1 (no note line above the header) counted
// repetitions from 0 and had no repetitions or analysed column; version 2 counts trials
// and repetitions from 1, as every table and progress line does.
const std::vector<std::string> kColumnsV1 = {
    "trial",      "amplitude_deg", "motion",        "repetition", "eta_valid",
    "eta_pct",    "loading_J",     "unloading_J",   "net_J",      "positive_J",
    "negative_J", "peak_power_W",  "peak_torque_Nm"};
const std::vector<std::string> kColumns = {
    "trial",    "amplitude_deg", "repetitions", "motion",       "repetition",
    "analysed", "eta_valid",     "eta_pct",     "loading_J",    "unloading_J",
    "net_J",    "positive_J",    "negative_J",  "peak_power_W", "peak_torque_Nm"};
// Version 3 appends the attachment's fit to version 2's columns.
const std::vector<std::string> kFitColumns = {
    "fit_valid", "stiffness_Nm_rad", "damping_Nms_rad", "offset_Nm", "residual_rms_Nm"};
std::vector<std::string> ColumnsV3() {
  std::vector<std::string> c = kColumns;
  c.insert(c.end(), kFitColumns.begin(), kFitColumns.end());
  return c;
}
constexpr const char* kNote =
    "# mjc windows.csv version 3: trial and repetition count from 1; analysed = 1 for "
    "the middle three flexions the tables use; the attachment's fit tau = k*theta + "
    "b*omega + offset per window (version 2 had no fit columns; version 1, without this "
    "line, counted repetitions from 0)";

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
    for (const BoardWindow* w :
         AnalysedFlexions(trials[t].windows, trials[t].repetitions)) {
      load.push_back(w->loading_J * 1e3);
      unload.push_back(w->unloading_J * 1e3);
      net.push_back(w->net_J() * 1e3);
      if (!w->eta_valid) {
        ++skipped;
        continue;
      }
      eta.push_back(w->eta_percent);
      all.push_back(w->eta_percent);
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
  // What the numbers are: the middle three flexions, as repetitions counted from 1.
  std::string which = "the middle three flexions";
  if (!trials.empty() && std::all_of(trials.begin(), trials.end(), [&](const auto& t) {
        return t.repetitions == trials.front().repetitions;
      })) {
    const RepetitionRange keep = AnalysedRepetitions(trials.front().repetitions);
    std::snprintf(line, sizeof line, " (repetitions %d-%d of %d)", keep.first + 1,
                  keep.first + keep.count, trials.front().repetitions);
    which += line;
  }
  out += repeatability
             ? "\nη mean and η std: the mean and the sample standard deviation (n − 1) "
               "of η over each trial's " +
                   which + "; overall: over every trial's analysed flexions together.\n"
             : "\nEach energy: mean ± standard error of the mean (sample standard "
               "deviation / √n) over " +
                   which + " at that amplitude; η: their mean.\n";
  if (skipped > 0) {
    std::snprintf(line, sizeof line,
                  "η leaves out %d analysed window(s) the board marked invalid.\n",
                  skipped);
    out += line;
  }
  return out;
}

std::string AttachmentTable(const std::vector<TrialWindows>& trials) {
  std::string out =
      "| trial | amplitude | k_i (N·m/rad) | b_i (N·m·s/rad) | τ_0 (N·m) | residual RMS "
      "(N·m) | fits |\n|---|---|---|---|---|---|---|\n";
  char line[200];
  for (std::size_t t = 0; t < trials.size(); ++t) {
    std::vector<double> k, b, offset, rms;
    int analysed = 0;
    for (const BoardWindow* w :
         AnalysedFlexions(trials[t].windows, trials[t].repetitions)) {
      ++analysed;
      if (!w->fit_valid) continue;
      k.push_back(w->stiffness_Nm_rad);
      b.push_back(w->damping_Nms_rad);
      offset.push_back(w->offset_Nm);
      rms.push_back(w->residual_rms_Nm);
    }
    if (k.empty()) {
      std::snprintf(line, sizeof line, "| %zu | %.0f° | n/a | n/a | n/a | n/a | 0/%d |\n",
                    t + 1, trials[t].amplitude_deg, analysed);
    } else {
      std::snprintf(line, sizeof line,
                    "| %zu | %.0f° | %.3f | %.4f | %.4f | %.5f | %zu/%d |\n", t + 1,
                    trials[t].amplitude_deg, Describe(k).mean, Describe(b).mean,
                    Describe(offset).mean, Describe(rms).mean, k.size(), analysed);
    }
    out += line;
  }
  out +=
      "\nThe attachment's least-squares fit τ = k_i·θ_j + b_i·θ̇_j + τ_0 per window, "
      "solved on the board; each value the mean over the analysed flexions the board "
      "could fit (fits: how many of them).\n";
  return out;
}

bool SameAmplitude(const std::vector<TrialWindows>& trials) {
  return std::all_of(trials.begin(), trials.end(), [&](const TrialWindows& t) {
    return t.amplitude_deg == trials.front().amplitude_deg;
  });
}

void WriteWindowsCsv(const std::vector<TrialWindows>& trials,
                     const std::filesystem::path& dir) {
  std::string text = std::string(kNote) + "\n" + Joined(ColumnsV3()) + "\n";
  for (std::size_t t = 0; t < trials.size(); ++t) {
    for (const BoardWindow& w : trials[t].windows) {
      const bool analysed =
          IsAnalysedFlexion(w.motion, w.repetition, trials[t].repetitions);
      text += Joined({std::to_string(t + 1),
                      CsvTable::Number(trials[t].amplitude_deg),
                      std::to_string(trials[t].repetitions),
                      w.motion == Motion::kFlexion ? "flexion" : "extension",
                      std::to_string(w.repetition + 1),
                      analysed ? "1" : "0",
                      w.eta_valid ? "1" : "0",
                      CsvTable::Number(w.eta_percent),
                      CsvTable::Number(w.loading_J),
                      CsvTable::Number(w.unloading_J),
                      CsvTable::Number(w.net_J()),
                      CsvTable::Number(w.positive_J),
                      CsvTable::Number(w.negative_J),
                      CsvTable::Number(w.peak_power_W),
                      CsvTable::Number(w.peak_torque_Nm),
                      w.fit_valid ? "1" : "0",
                      CsvTable::Number(w.stiffness_Nm_rad),
                      CsvTable::Number(w.damping_Nms_rad),
                      CsvTable::Number(w.offset_Nm),
                      CsvTable::Number(w.residual_rms_Nm)}) +
              "\n";
    }
  }
  WriteFile(dir / "windows.csv", text);
}

std::optional<std::vector<TrialWindows>> ReadWindowsCsv(const std::filesystem::path& dir,
                                                        std::string* why, int* version) {
  const std::filesystem::path path = dir / "windows.csv";
  std::ifstream in(path);
  if (!in) {
    *why = "no windows.csv in " + dir.string() + " (write one with mjc trial --out)";
    return std::nullopt;
  }
  std::string line;
  std::getline(in, line);
  int number = 1;
  const bool v3 = line.starts_with("# mjc windows.csv version 3");
  const bool v2 = v3 || line.starts_with("# mjc windows.csv version 2");
  if (v2) {
    std::getline(in, line);
    ++number;
  }
  const std::vector<std::string> columns = v3 ? ColumnsV3() : v2 ? kColumns : kColumnsV1;
  if (line != Joined(columns)) {
    *why = path.string() + ": the header is not '" + Joined(columns) +
           "' (written by another version of mjc trial?)";
    return std::nullopt;
  }
  if (version != nullptr) *version = v3 ? 3 : v2 ? 2 : 1;
  // Version 1's cells in version 2's places (no repetitions or analysed column).
  const std::vector<int> at =
      v2 ? std::vector<int>{0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 11, 12, 13, 14}
         : std::vector<int>{0, 1, -1, 2, 3, -1, 4, 5, 6, 7, 9, 10, 11, 12};
  std::vector<TrialWindows> trials;
  std::vector<bool> planned;  // the file gave the trial's repetitions
  while (std::getline(in, line)) {
    ++number;
    std::vector<std::string> cell;
    std::stringstream row(line);
    for (std::string c; std::getline(row, c, ',');) cell.push_back(c);
    try {
      if (cell.size() != columns.size()) throw std::invalid_argument("cells");
      const auto get = [&](int i) -> const std::string& {
        return cell[static_cast<std::size_t>(at[static_cast<std::size_t>(i)])];
      };
      if (get(3) != "flexion" && get(3) != "extension")
        throw std::invalid_argument("motion");
      if (get(6) != "0" && get(6) != "1") throw std::invalid_argument("eta_valid");
      const auto t = static_cast<std::size_t>(std::stoul(get(0)));
      // Counted from 1 in version 2, from 0 in version 1; kept from 0 here, as the
      // board counts.
      const unsigned long counted = std::stoul(get(4));
      if (v2 && counted == 0) throw std::out_of_range("repetition");
      const unsigned long repetition = v2 ? counted - 1 : counted;
      if (t == 0 || t > 10000 || repetition > 0xFFFE) throw std::out_of_range("range");
      if (trials.size() < t) {
        trials.resize(t);
        planned.resize(t, false);
      }
      TrialWindows& tw = trials[t - 1];
      tw.amplitude_deg = std::stod(get(1));
      BoardWindow w;
      w.motion = get(3) == "flexion" ? Motion::kFlexion : Motion::kExtension;
      w.repetition = static_cast<std::uint16_t>(repetition);
      w.eta_valid = get(6) == "1";
      w.eta_percent = std::stod(get(7));
      w.loading_J = std::stod(get(8));
      w.unloading_J = std::stod(get(9));
      w.positive_J = std::stod(get(10));
      w.negative_J = std::stod(get(11));
      w.peak_power_W = std::stod(get(12));
      w.peak_torque_Nm = std::stod(get(13));
      if (v3) {
        const std::string& valid = cell[kColumns.size()];
        if (valid != "0" && valid != "1") throw std::invalid_argument("fit_valid");
        w.fit_valid = valid == "1";
        w.stiffness_Nm_rad = std::stod(cell[kColumns.size() + 1]);
        w.damping_Nms_rad = std::stod(cell[kColumns.size() + 2]);
        w.offset_Nm = std::stod(cell[kColumns.size() + 3]);
        w.residual_rms_Nm = std::stod(cell[kColumns.size() + 4]);
      }
      if (v2) {
        const unsigned long reps = std::stoul(get(2));
        if (reps == 0 || reps > 255 || repetition >= reps)
          throw std::out_of_range("reps");
        tw.repetitions = static_cast<std::uint16_t>(reps);
        planned[t - 1] = true;
      } else {
        tw.repetitions =
            std::max(tw.repetitions, static_cast<std::uint16_t>(w.repetition + 1));
      }
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

bool PlotTrials(const std::filesystem::path& dir, bool repeatability,
                const std::string& title, std::string* why, const std::string& data) {
  // Columns (version 2): 1 trial, 2 amplitude_deg, 4 motion, 6 analysed, 7 eta_valid,
  // 8 eta_pct. Single quotes in the title would end gnuplot's string.
  std::string quoted = title;
  std::replace(quoted.begin(), quoted.end(), '\'', '"');
  const std::string x = repeatability ? "1" : "2";
  const std::string flexion = "(strcol(4) eq 'flexion' && $7 == 1 && $6 == ";
  const auto script = dir / "eta.gp";
  WriteFile(script, std::string("set terminal pngcairo size 900,600\n"
                                "set output 'eta.png'\n"
                                "set datafile separator ','\nset grid\n") +
                        "set title '" + quoted + "'\n" +
                        (repeatability ? "set xlabel 'trial (number, from 1)'\n"
                                       : "set xlabel 'amplitude (°)'\n") +
                        "set ylabel 'energy loss η (%)'\n"
                        "set key outside top center horizontal\n"
                        "plot '" +
                        data + "' every ::1 using " + x + ":" + flexion +
                        "1 ? $8 : 1/0) with points pt 7 ps 1.2 " +
                        "title 'analysed flexions (the middle three of each trial)', \\\n"
                        "     '" +
                        data + "' every ::1 using " + x + ":" + flexion +
                        "0 ? $8 : 1/0) with points pt 6 ps 1.0 " +
                        "title 'other flexions'\n");
  return RunGnuplot(script, why);
}

}  // namespace mjc::host
