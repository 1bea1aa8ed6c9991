#include "mjc/host/trial_report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <map>
#include <sstream>
#include <stdexcept>
#include <tuple>

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

namespace {

std::string Header() { return std::string(kNote) + "\n" + Joined(ColumnsV3()) + "\n"; }

// A window's row, with its newline.
std::string Row(std::size_t trial, double amplitude_deg, std::uint16_t repetitions,
                const BoardWindow& w) {
  const bool analysed = IsAnalysedFlexion(w.motion, w.repetition, repetitions);
  return Joined({std::to_string(trial + 1),
                 CsvTable::Number(amplitude_deg),
                 std::to_string(repetitions),
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

}  // namespace

void WriteWindowsCsv(const std::vector<TrialWindows>& trials,
                     const std::filesystem::path& dir) {
  std::string text = Header();
  for (std::size_t t = 0; t < trials.size(); ++t) {
    for (const BoardWindow& w : trials[t].windows) {
      text += Row(t, trials[t].amplitude_deg, trials[t].repetitions, w);
    }
  }
  WriteFile(dir / "windows.csv", text);
}

WindowsCsvWriter::WindowsCsvWriter(const std::filesystem::path& dir)
    : file_(dir / "windows.csv") {
  file_.Append(Header());
}

void WindowsCsvWriter::Append(std::size_t trial, double amplitude_deg,
                              std::uint16_t repetitions, const BoardWindow& w) {
  file_.Append(Row(trial, amplitude_deg, repetitions, w));
  ++rows_;
}

namespace {

// A cell that is wrong, named by its line and column: "line 5, loading_J: …".
struct CellError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// A number the file can hold: decimal (no nan, inf, hex), finite, and within what the
// board's frames can carry (`lo`, `hi`: the wire format's range).
double Number(const std::string& text, const std::string& name, double lo, double hi) {
  const bool decimal =
      !text.empty() && text.find_first_not_of("0123456789+-.eE") == std::string::npos;
  char* end = nullptr;
  const double v = decimal ? std::strtod(text.c_str(), &end) : 0;
  if (!decimal || end != text.c_str() + text.size() || !std::isfinite(v)) {
    throw CellError(name + ": '" + text + "' is not a finite decimal number");
  }
  if (v < lo || v > hi) {
    throw CellError(name + ": " + text + " is outside [" + CsvTable::Number(lo) + ", " +
                    CsvTable::Number(hi) + "]");
  }
  return v;
}

unsigned long Count(const std::string& text, const std::string& name, unsigned long lo,
                    unsigned long hi) {
  const bool digits = !text.empty() && text.size() <= 6 &&
                      text.find_first_not_of("0123456789") == std::string::npos;
  const unsigned long v = digits ? std::stoul(text) : 0;
  if (!digits || v < lo || v > hi) {
    throw CellError(name + ": '" + text + "' is not a whole number in [" +
                    std::to_string(lo) + ", " + std::to_string(hi) + "]");
  }
  return v;
}

bool Flag(const std::string& text, const std::string& name) {
  if (text != "0" && text != "1")
    throw CellError(name + ": '" + text + "' is not 0 or 1");
  return text == "1";
}

// The wire's ranges: energies, power and torques travel as Q7.24, η as Q15.16.
constexpr double kQ7_24 = 128.0;
constexpr double kQ15_16 = 32768.0;

}  // namespace

std::optional<std::vector<TrialWindows>> ReadWindowsCsv(const std::filesystem::path& dir,
                                                        std::string* why, int* version,
                                                        bool* cut_last) {
  const std::filesystem::path path = dir / "windows.csv";
  const auto text = ReadFileText(path);
  if (!text) {
    if (cut_last != nullptr) *cut_last = false;
    *why = "no windows.csv in " + dir.string() + " (write one with mjc trial --out)";
    return std::nullopt;
  }
  return ParseWindowsCsv(*text, path.string(), why, version, cut_last);
}

std::optional<std::vector<TrialWindows>> ParseWindowsCsv(const std::string& all,
                                                         const std::string& source,
                                                         std::string* why, int* version,
                                                         bool* cut_last) {
  if (cut_last != nullptr) *cut_last = false;

  std::vector<std::string> lines;
  for (std::size_t at = 0; at < all.size();) {
    const std::size_t end = all.find('\n', at);
    lines.push_back(all.substr(at, end == std::string::npos ? end : end - at));
    at = end == std::string::npos ? all.size() : end + 1;
  }
  // The last row without its newline: the writer stopped in the middle of it (each
  // row is appended whole with its newline, so only a dying writer leaves one). It is
  // left out, and said.
  const bool cut = !all.empty() && all.back() != '\n' && lines.size() > 2;
  if (cut) {
    lines.pop_back();
    if (cut_last != nullptr) *cut_last = true;
  }
  std::size_t next = 0;
  std::string line = next < lines.size() ? lines[next++] : "";
  int number = 1;
  const bool v3 = line.starts_with("# mjc windows.csv version 3");
  const bool v2 = v3 || line.starts_with("# mjc windows.csv version 2");
  if (v2) {
    line = next < lines.size() ? lines[next++] : "";
    ++number;
  }
  const std::vector<std::string> columns = v3 ? ColumnsV3() : v2 ? kColumns : kColumnsV1;
  if (line != Joined(columns)) {
    *why = source + ": the header is not '" + Joined(columns) +
           "' (written by another version of mjc trial?)";
    return std::nullopt;
  }
  if (version != nullptr) *version = v3 ? 3 : v2 ? 2 : 1;
  // Version 1's cells in version 2's places (no repetitions or analysed column).
  const std::vector<int> at =
      v2 ? std::vector<int>{0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14}
         : std::vector<int>{0, 1, -1, 2, 3, -1, 4, 5, 6, 7, 8, 9, 10, 11, 12};
  std::vector<TrialWindows> trials;
  std::vector<bool> planned;    // the file gave the trial's repetitions
  std::vector<int> trial_line;  // the line that first gave each trial's amplitude
  // Each window once: (trial, motion, repetition) -> its line.
  std::map<std::tuple<std::size_t, int, unsigned long>, int> seen;
  while (next < lines.size()) {
    line = lines[next++];
    ++number;
    const std::string where = source + ": line " + std::to_string(number);
    std::vector<std::string> cell;
    std::stringstream row(line);
    for (std::string c; std::getline(row, c, ',');) cell.push_back(c);
    if (!line.empty() && line.back() == ',') cell.push_back("");
    try {
      if (cell.size() != columns.size()) {
        throw CellError("has " + std::to_string(cell.size()) +
                        " cells where the header has " + std::to_string(columns.size()));
      }
      const auto get = [&](int i) -> const std::string& {
        return cell[static_cast<std::size_t>(at[static_cast<std::size_t>(i)])];
      };
      const auto name = [&](int i) {
        return columns[static_cast<std::size_t>(at[static_cast<std::size_t>(i)])];
      };
      if (get(3) != "flexion" && get(3) != "extension") {
        throw CellError("motion: '" + get(3) + "' is not flexion or extension");
      }
      const auto t = static_cast<std::size_t>(Count(get(0), "trial", 1, 10000));
      // Counted from 1 in version 2, from 0 in version 1; kept from 0 here, as the
      // board counts.
      const unsigned long counted = Count(get(4), "repetition", v2 ? 1 : 0, 0xFFFF);
      const unsigned long repetition = v2 ? counted - 1 : counted;
      if (trials.size() < t) {
        trials.resize(t);
        planned.resize(t, false);
        trial_line.resize(t, 0);
      }
      TrialWindows& tw = trials[t - 1];
      const double amplitude = Number(get(1), "amplitude_deg", 1, 90);
      if (trial_line[t - 1] != 0 && amplitude != tw.amplitude_deg) {
        throw CellError("amplitude_deg: " + get(1) + "° contradicts line " +
                        std::to_string(trial_line[t - 1]) + "'s " +
                        CsvTable::Number(tw.amplitude_deg) + "° for trial " +
                        std::to_string(t));
      }
      BoardWindow w;
      w.motion = get(3) == "flexion" ? Motion::kFlexion : Motion::kExtension;
      w.repetition = static_cast<std::uint16_t>(repetition);
      w.eta_valid = Flag(get(6), name(6));
      w.eta_percent = Number(get(7), name(7), -kQ15_16, kQ15_16);
      w.loading_J = Number(get(8), name(8), -kQ7_24, kQ7_24);
      w.unloading_J = Number(get(9), name(9), -kQ7_24, kQ7_24);
      if (v2) {
        // net_J is loading + unloading (%.9g of each: a few parts in 1e9).
        const double net = Number(get(10), name(10), -2 * kQ7_24, 2 * kQ7_24);
        const double sum = w.loading_J + w.unloading_J;
        if (std::abs(net - sum) >
            1e-8 * (std::abs(w.loading_J) + std::abs(w.unloading_J)) + 1e-15) {
          throw CellError("net_J: " + get(10) + " is not loading_J + unloading_J (" +
                          CsvTable::Number(sum) + ")");
        }
      }
      // ∫max(P, 0) and ∫min(P, 0).
      w.positive_J = Number(get(11), name(11), 0, kQ7_24);
      w.negative_J = Number(get(12), name(12), -kQ7_24, 0);
      w.peak_power_W = Number(get(13), name(13), -kQ7_24, kQ7_24);
      w.peak_torque_Nm = Number(get(14), name(14), -kQ7_24, kQ7_24);
      // η = (1 − |E_unloading| / E_loading) · 100 %, formed only when E_loading > 0.
      if (w.eta_valid && w.loading_J <= 0) {
        throw CellError(name(8) + ": " + get(8) +
                        " is not positive, yet eta_valid says η was formed from it");
      }
      if (w.eta_valid && w.eta_percent > 100) {
        throw CellError(name(7) + ": " + get(7) +
                        " is above 100 % (η = 1 − |E_u| / E_l)");
      }
      if (v3) {
        const std::size_t f = kColumns.size();
        w.fit_valid = Flag(cell[f], kFitColumns[0]);
        w.stiffness_Nm_rad = Number(cell[f + 1], kFitColumns[1], -kQ7_24, kQ7_24);
        w.damping_Nms_rad = Number(cell[f + 2], kFitColumns[2], -kQ7_24, kQ7_24);
        w.offset_Nm = Number(cell[f + 3], kFitColumns[3], -kQ7_24, kQ7_24);
        w.residual_rms_Nm = Number(cell[f + 4], kFitColumns[4], 0, kQ7_24);
      }
      if (v2) {
        const unsigned long reps = Count(get(2), "repetitions", 1, 255);
        if (repetition >= reps) {
          throw CellError("repetition: " + get(4) + " is beyond the trial's " + get(2) +
                          " repetitions");
        }
        if (planned[t - 1] && reps != tw.repetitions) {
          throw CellError("repetitions: " + get(2) + " contradicts line " +
                          std::to_string(trial_line[t - 1]) + "'s " +
                          std::to_string(tw.repetitions) + " for trial " +
                          std::to_string(t));
        }
        const bool analysed = Flag(get(5), name(5));
        if (analysed !=
            IsAnalysedFlexion(w.motion, w.repetition, static_cast<std::uint16_t>(reps))) {
          throw CellError("analysed: " + get(5) + " contradicts the window (" + get(3) +
                          " " + get(4) + " of " + get(2) + ")");
        }
        tw.repetitions = static_cast<std::uint16_t>(reps);
        planned[t - 1] = true;
      } else {
        tw.repetitions =
            std::max(tw.repetitions, static_cast<std::uint16_t>(w.repetition + 1));
      }
      const auto key = std::make_tuple(t, static_cast<int>(w.motion), repetition);
      if (const auto it = seen.find(key); it != seen.end()) {
        throw CellError("the " + get(3) + " of repetition " + get(4) + " of trial " +
                        get(0) + " again (first on line " + std::to_string(it->second) +
                        ")");
      }
      seen[key] = number;
      if (trial_line[t - 1] == 0) trial_line[t - 1] = number;
      tw.amplitude_deg = amplitude;
      tw.windows.push_back(w);
    } catch (const CellError& e) {
      *why = where + ", " + e.what();
      return std::nullopt;
    } catch (const std::exception&) {
      *why = where + " is malformed";
      return std::nullopt;
    }
  }
  if (trials.empty()) {
    *why = source + " holds no windows";
    return std::nullopt;
  }
  for (std::size_t t = 0; t < trials.size(); ++t) {
    if (trial_line[t] == 0) {
      *why = source + ": trial " + std::to_string(t + 1) +
             " has no window, though a later trial has";
      return std::nullopt;
    }
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
