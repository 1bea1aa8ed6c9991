#include "sweep.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <limits>
#include <map>
#include <mutex>
#include <numbers>
#include <random>
#include <set>
#include <span>
#include <stdexcept>
#include <thread>
#include <tuple>

#include "mjc/host/report.h"

namespace mjc::paper {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

constexpr double kDeg = 180.0 / std::numbers::pi;
constexpr std::uint16_t kMinRepetitions = 3;  // the analysed middle three
constexpr std::uint16_t kMaxRepetitions = 50;
constexpr std::size_t kMaxPoints = 100000;
constexpr std::string_view kModelNames[] = {"kelvin_voigt", "standard_linear_solid"};

// The ranges: the plant's own for the attachment (plant/params.h); the amplitude within
// the ±30° the calibration sweep covers; the drive frequencies the scenarios are checked
// at; spring rates that keep K = 2·k·r_j² within 0.2–2 N·m/rad at r_j = 1 cm (the
// default spring is 3150 N/m); slacks from a quarter to five times the default 2°, all
// of which the calibration fit finds (a slack wider than the amplitude leaves the cable
// idle: such a point's truth is ~0 and its board numbers are noise, which is a finding).
constexpr SweepAxisInfo kAxes[kSweepAxes] = {
    {"stiffness_Nm_per_rad", "N·m/rad", 0.0, 1000.0},
    {"damping_Nm_s_per_rad", "N·m·s/rad", 0.0, 100.0},
    {"model", "", 0.0, 1.0},
    {"maxwell_stiffness_Nm_per_rad", "N·m/rad", 0.0, 1000.0},
    {"preload_Nm", "N·m", -1.0, 1.0},
    {"amplitude_deg", "°", 1.0, 30.0},
    {"frequency_hz", "Hz", sim::kMinDriveFrequencyHz, sim::kMaxDriveFrequencyHz},
    {"spring_rate_N_per_m", "N/m", 1000.0, 10000.0},
    {"cable_slack_deg", "°", 0.5, 10.0},
};
constexpr std::string_view kTopKeys[] = {"robot", "subject", "repetitions",
                                         "seed",  "axes",    "maps"};

std::string Num(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", v);
  return text;
}

// Exact: a double written with 17 significant digits reads back as the same double, so
// a summary made from the files equals one made from the trials.
std::string Exact(double v) {
  char text[40];
  std::snprintf(text, sizeof text, "%.17g", v);
  return text;
}

std::string Fixed(const char* format, double v) {
  char text[40];
  std::snprintf(text, sizeof text, format, v);
  return text;
}

[[noreturn]] void Refuse(std::string_view source, const std::string& what) {
  throw std::runtime_error(std::string(source) + ": " + what);
}

std::string Known(std::span<const std::string_view> keys) {
  std::string out;
  for (const std::string_view k : keys) out += (out.empty() ? "" : ", ") + std::string(k);
  return out;
}

std::string AxisKeys() {
  std::vector<std::string_view> keys;
  for (const SweepAxisInfo& a : kAxes) keys.push_back(a.key);
  return Known(keys);
}

std::optional<SweepAxis> AxisByKey(std::string_view key) {
  for (std::size_t i = 0; i < kSweepAxes; ++i) {
    if (kAxes[i].key == key) return static_cast<SweepAxis>(i);
  }
  return std::nullopt;
}

std::size_t Index(SweepAxis a) { return static_cast<std::size_t>(a); }

std::string ValueText(SweepAxis axis, double v) {
  if (axis == SweepAxis::kModel) return std::string(kModelNames[v > 0.5 ? 1 : 0]);
  return Num(v);
}

// A point's values on the axes that vary, "key=value ...", for messages.
std::string PointAxes(const std::array<std::vector<double>, kSweepAxes>& values,
                      const std::array<double, kSweepAxes>& value) {
  std::string out;
  for (std::size_t a = 0; a < kSweepAxes; ++a) {
    if (values[a].size() < 2) continue;
    out += (out.empty() ? "" : " ") + std::string(kAxes[a].key) + "=" +
           ValueText(static_cast<SweepAxis>(a), value[a]);
  }
  return out;
}

std::uint64_t Fnv1a64(std::string_view text) {
  std::uint64_t h = 14695981039346656037ull;
  for (const char c : text) {
    h ^= static_cast<std::uint8_t>(c);
    h *= 1099511628211ull;
  }
  return h;
}

// The sensor-noise seed of a point's trial (`domain` 1) or a variant's calibration
// (2): std::seed_seq's mixing is specified by the standard, so the same everywhere,
// and it depends on the point's index in the whole grid, not on a shard or a thread.
std::uint64_t Seed(std::uint64_t seed, std::uint32_t domain, std::size_t index) {
  std::seed_seq mix{static_cast<std::uint32_t>(seed),
                    static_cast<std::uint32_t>(seed >> 32), domain,
                    static_cast<std::uint32_t>(index)};
  std::uint32_t words[2];
  mix.generate(std::begin(words), std::end(words));
  return (std::uint64_t{words[0]} << 32) | words[1];
}

plant::PlantParams Load(const std::string& name_or_path) {
  if (name_or_path.find('/') != std::string::npos || name_or_path.ends_with(".json")) {
    return plant::LoadPlantParamsFile(name_or_path);
  }
  return plant::LoadPlantParams(name_or_path);
}

// The per-axis indices of point `index` of a product with `sizes` (last fastest).
std::array<std::size_t, kSweepAxes> Digits(
    std::size_t index, const std::array<std::size_t, kSweepAxes>& sizes) {
  std::array<std::size_t, kSweepAxes> d{};
  for (std::size_t a = kSweepAxes; a-- > 0;) {
    d[a] = index % sizes[a];
    index /= sizes[a];
  }
  return d;
}

// What the summary needs of a sweep, as grid.json holds it.
struct Resolved {
  std::string digest;
  std::array<std::vector<double>, kSweepAxes> values;
  std::uint16_t repetitions = 5;
  std::vector<std::array<SweepAxis, 2>> maps;
  std::size_t points = 0;
  std::array<std::size_t, kSweepAxes> Sizes() const {
    std::array<std::size_t, kSweepAxes> s{};
    for (std::size_t a = 0; a < kSweepAxes; ++a) s[a] = values[a].size();
    return s;
  }
  double Value(std::size_t index, SweepAxis axis) const {
    return values[Index(axis)][Digits(index, Sizes())[Index(axis)]];
  }
};

json ResolvedJson(const std::array<std::vector<double>, kSweepAxes>& values) {
  json axes = json::object();
  for (std::size_t a = 0; a < kSweepAxes; ++a) {
    json list = json::array();
    for (const double v : values[a]) {
      if (static_cast<SweepAxis>(a) == SweepAxis::kModel) {
        list.push_back(ValueText(SweepAxis::kModel, v));
      } else {
        list.push_back(v);
      }
    }
    axes[std::string(kAxes[a].key)] = list;
  }
  return axes;
}

Resolved ReadResolved(const fs::path& folder) {
  const fs::path path = folder / "grid.json";
  const auto text = host::ReadFileText(path);
  if (!text)
    throw std::runtime_error(path.string() + ": not a sweep's folder (no grid.json)");
  try {
    const json j = json::parse(*text);
    Resolved r;
    r.digest = j.at("digest").get<std::string>();
    r.repetitions = j.at("repetitions").get<std::uint16_t>();
    r.points = j.at("points").get<std::size_t>();
    const json& axes = j.at("resolved");
    for (std::size_t a = 0; a < kSweepAxes; ++a) {
      for (const json& v : axes.at(std::string(kAxes[a].key))) {
        if (static_cast<SweepAxis>(a) == SweepAxis::kModel) {
          r.values[a].push_back(v.get<std::string>() == kModelNames[1] ? 1.0 : 0.0);
        } else {
          r.values[a].push_back(v.get<double>());
        }
      }
    }
    for (const json& m : j.at("maps")) {
      r.maps.push_back({*AxisByKey(m.at(0).get<std::string>()),
                        *AxisByKey(m.at(1).get<std::string>())});
    }
    return r;
  } catch (const std::exception& e) {
    throw std::runtime_error(path.string() + ": unreadable (" + e.what() + ")");
  }
}

fs::path PointPath(const fs::path& out, std::size_t index, const char* ext) {
  char name[32];
  std::snprintf(name, sizeof name, "p%05zu.%s", index, ext);
  return out / "points" / name;
}

const char* kWindowColumns =
    "motion,repetition,analysed,load_J,truth_load_J,unload_J,truth_unload_J,net_J,"
    "truth_net_J,eta_pct,truth_eta_pct,fit_valid,stiffness_Nm_rad,damping_Nms_rad,"
    "offset_Nm,residual_rms_Nm\n";

// The point's windows (board beside truth, energies, η, the attachment fit), then its
// trial's figures in the .json; each replaced whole (temporary file and rename), the
// .json last: a point with both is complete.
void WritePoint(const fs::path& out, const Resolved& grid, const SweepPoint& point,
                std::uint64_t noise_seed, const sim::TrialOutcome& trial) {
  std::string csv = kWindowColumns;
  for (const sim::WindowOutcome& w : trial.windows) {
    const bool analysed =
        host::IsAnalysedFlexion(w.motion, w.repetition, grid.repetitions);
    csv += std::string(w.motion == Motion::kFlexion ? "flexion" : "extension") + "," +
           std::to_string(w.repetition) + "," + (analysed ? "1" : "0");
    for (const double v : {w.load, w.truth_load, w.unload, w.truth_unload, w.net,
                           w.truth_net, w.eta, w.truth_eta}) {
      csv += "," + Exact(v);
    }
    csv += std::string(",") + (w.fit_valid ? "1" : "0");
    for (const double v : {w.stiffness, w.damping, w.offset, w.residual_rms}) {
      csv += "," + Exact(v);
    }
    csv += "\n";
  }
  host::ReplaceFile(PointPath(out, point.index, "csv"), csv);
  const double frequency = point.value[Index(SweepAxis::kFrequency)];
  const sim::InterfaceTruth truth = sim::TrueInterface(point.interface, frequency);
  json axes = json::object();
  for (std::size_t a = 0; a < kSweepAxes; ++a) {
    if (static_cast<SweepAxis>(a) == SweepAxis::kModel) {
      axes[std::string(kAxes[a].key)] = ValueText(SweepAxis::kModel, point.value[a]);
    } else {
      axes[std::string(kAxes[a].key)] = point.value[a];
    }
  }
  const json j = {{"digest", grid.digest},
                  {"index", point.index},
                  {"axes", axes},
                  {"noise_seed", noise_seed},
                  {"ticks", trial.ticks},
                  {"power_rmse_W", trial.power_rmse_W},
                  {"truth_peak_power_W", trial.truth_peak_power_W},
                  {"faulted", trial.faulted},
                  {"fault", trial.fault},
                  {"true_stiffness_Nm_rad", truth.stiffness},
                  {"true_damping_Nms_rad", truth.damping}};
  host::ReplaceFile(PointPath(out, point.index, "json"), j.dump(1) + "\n");
}

std::vector<std::string> Split(const std::string& line) {
  std::vector<std::string> cells;
  std::size_t from = 0;
  for (;;) {
    const std::size_t comma = line.find(',', from);
    cells.push_back(line.substr(from, comma - from));
    if (comma == std::string::npos) return cells;
    from = comma + 1;
  }
}

bool ParseDouble(const std::string& cell, double* v) {
  char* end = nullptr;
  *v = std::strtod(cell.c_str(), &end);
  return !cell.empty() && end == cell.c_str() + cell.size();
}

std::optional<SweepPointResult> ReadPoint(const fs::path& out, std::size_t index,
                                          const std::string& digest) {
  const auto meta = host::ReadFileText(PointPath(out, index, "json"));
  const auto csv = host::ReadFileText(PointPath(out, index, "csv"));
  if (!meta || !csv) return std::nullopt;
  SweepPointResult r;
  try {
    const json j = json::parse(*meta);
    if (!digest.empty() && j.at("digest").get<std::string>() != digest)
      return std::nullopt;
    if (j.at("index").get<std::size_t>() != index) return std::nullopt;
    r.trial.ticks = j.at("ticks").get<std::uint32_t>();
    r.trial.power_rmse_W = j.at("power_rmse_W").get<double>();
    r.trial.truth_peak_power_W = j.at("truth_peak_power_W").get<double>();
    r.trial.faulted = j.at("faulted").get<bool>();
    r.trial.fault = j.at("fault").get<std::string>();
    r.truth.stiffness = j.at("true_stiffness_Nm_rad").get<double>();
    r.truth.damping = j.at("true_damping_Nms_rad").get<double>();
  } catch (const std::exception&) {
    return std::nullopt;
  }
  std::size_t from = 0;
  bool header = true;
  while (from < csv->size()) {
    const std::size_t nl = csv->find('\n', from);
    if (nl == std::string::npos) return std::nullopt;  // cut short
    const std::string line = csv->substr(from, nl - from);
    from = nl + 1;
    if (header) {
      if (line + "\n" != kWindowColumns) return std::nullopt;
      header = false;
      continue;
    }
    const std::vector<std::string> c = Split(line);
    if (c.size() != 16) return std::nullopt;
    sim::WindowOutcome w;
    w.motion = c[0] == "flexion" ? Motion::kFlexion : Motion::kExtension;
    double num[16] = {};
    for (std::size_t i = 1; i < 16; ++i) {
      if (!ParseDouble(c[i], &num[i])) return std::nullopt;
    }
    w.repetition = static_cast<std::uint16_t>(num[1]);
    w.load = num[3];
    w.truth_load = num[4];
    w.unload = num[5];
    w.truth_unload = num[6];
    w.net = num[7];
    w.truth_net = num[8];
    w.eta = num[9];
    w.truth_eta = num[10];
    w.fit_valid = num[11] != 0;
    w.stiffness = num[12];
    w.damping = num[13];
    w.offset = num[14];
    w.residual_rms = num[15];
    r.trial.windows.push_back(w);
  }
  if (header) return std::nullopt;
  return r;
}

// One row of the summary: the point's axes, then what the summary says of its trial.
struct Row {
  std::size_t index = 0;
  sim::AmplitudePoint point;
  SweepPointResult result;
};

std::string Cell(double v, const char* format = "%.3g") { return Fixed(format, v); }

// A ratio to a point's loading work (η, the power error as % of its peak) means
// something only when that work stands above the noise: twice the standard error of
// the board's loading means, and the table's resolution, 1 µJ (a work printed as
// 0.000 mJ: a cable slack wider than the motion moves the joint not at all). Otherwise
// the cell says why there is no figure.
// sweep.csv has nan there.
constexpr double kWorkResolution_J = 1e-6;
double RatioFloor(const host::Stats& board_load) {
  return std::max(2 * board_load.se, kWorkResolution_J);
}
double Judged(double v, double load_J, const host::Stats& board_load) {
  return load_J > RatioFloor(board_load) ? v : std::numeric_limits<double>::quiet_NaN();
}
std::string RatioCell(double v, double load_J, const host::Stats& board_load,
                      const char* format) {
  const double floor = RatioFloor(board_load);
  if (!(load_J > floor)) {
    return "n/a (loading " + Fixed("%.4f", 1e3 * load_J) + " mJ, within " +
           Fixed("%.4f", 1e3 * floor) + " mJ)";
  }
  return std::isfinite(v) ? Fixed(format, v) : std::string("n/a");
}

// The summary's table also goes to stdout, as the other scenarios print theirs.
void WriteSummary(const fs::path& out, const Resolved& grid) {
  std::vector<Row> rows;
  std::vector<std::size_t> missing;
  for (std::size_t i = 0; i < grid.points; ++i) {
    auto r = ReadPoint(out, i, grid.digest);
    if (!r) {
      missing.push_back(i);
      continue;
    }
    Row row;
    row.index = i;
    row.point = sim::SummarisePoint(grid.Value(i, SweepAxis::kAmplitude), r->trial,
                                    grid.repetitions);
    row.result = std::move(*r);
    rows.push_back(std::move(row));
  }
  if (!missing.empty()) {
    throw std::runtime_error(std::to_string(missing.size()) + " of " +
                             std::to_string(grid.points) + " points missing in " +
                             out.string() + " (the first: " + std::to_string(missing[0]) +
                             ")");
  }

  // sweep.csv: every axis, board and truth.
  std::string csv = "index";
  for (const SweepAxisInfo& a : kAxes) csv += "," + std::string(a.key);
  csv +=
      ",flexions,eta_pct,truth_eta_pct,load_mJ,truth_load_mJ,unload_mJ,truth_unload_mJ,"
      "net_mJ,truth_net_mJ,power_rmse_pct_peak,fits,stiffness_Nm_rad,true_stiffness_Nm_"
      "rad,damping_Nms_rad,true_damping_Nms_rad,faulted\n";
  for (const Row& r : rows) {
    csv += std::to_string(r.index);
    for (std::size_t a = 0; a < kSweepAxes; ++a) {
      csv += "," + ValueText(static_cast<SweepAxis>(a),
                             grid.Value(r.index, static_cast<SweepAxis>(a)));
    }
    const sim::AmplitudePoint& p = r.point;
    csv += "," + std::to_string(p.eta.n);
    for (const double v :
         {Judged(p.eta.mean, p.load.mean, p.load),
          Judged(p.truth_eta.mean, p.truth_load.mean, p.load), 1e3 * p.load.mean,
          1e3 * p.truth_load.mean, 1e3 * p.unload.mean, 1e3 * p.truth_unload.mean,
          1e3 * p.net.mean, 1e3 * p.truth_net.mean,
          Judged(p.power_rmse_pct_peak, p.truth_load.mean, p.load)}) {
      csv += "," + host::CsvTable::Number(v);
    }
    csv += "," + std::to_string(p.stiffness.n);
    for (const double v : {p.stiffness.mean, r.result.truth.stiffness, p.damping.mean,
                           r.result.truth.damping}) {
      csv += "," + host::CsvTable::Number(v);
    }
    csv += std::string(",") + (r.result.trial.faulted ? "1" : "0") + "\n";
  }
  host::ReplaceFile(out / "sweep.csv", csv);

  // sweep.md: the axes that vary, the fixed ones above the table.
  std::vector<SweepAxis> varying;
  std::string fixed;
  for (std::size_t a = 0; a < kSweepAxes; ++a) {
    const auto axis = static_cast<SweepAxis>(a);
    if (grid.values[a].size() > 1) {
      varying.push_back(axis);
    } else {
      fixed += (fixed.empty() ? "" : ", ") + std::string(kAxes[a].key) + " = " +
               ValueText(axis, grid.values[a][0]);
    }
  }
  std::string md = "# Design-space sweep\n\nGrid " + grid.digest + ": " +
                   std::to_string(grid.points) + " points, each a trial of " +
                   std::to_string(grid.repetitions) +
                   " cycles on a board calibrated for its robot variant; the middle "
                   "three flexions analysed (means). Board: the firmware's estimate; "
                   "truth: the plant's. Work per flexion in mJ; k, b identified by the "
                   "board's attachment fit (its b includes the joint's bearings) beside "
                   "the attachment's true values at the drive frequency.\n\n";
  if (!fixed.empty()) md += "Fixed: " + fixed + ".\n\n";
  md += "| # |";
  for (const SweepAxis a : varying) md += " " + std::string(kAxes[Index(a)].key) + " |";
  md +=
      " η board % | η truth % | net board | net truth | P RMSE % peak | k id | k true | "
      "b id | b true |\n|---|";
  for (std::size_t i = 0; i < varying.size() + 9; ++i) md += "---|";
  md += "\n";
  for (const Row& r : rows) {
    const sim::AmplitudePoint& p = r.point;
    md += "| " + std::to_string(r.index) + " |";
    for (const SweepAxis a : varying)
      md += " " + ValueText(a, grid.Value(r.index, a)) + " |";
    if (r.result.trial.faulted) {
      md += " faulted: " + r.result.trial.fault + " |";
      for (int i = 0; i < 8; ++i) md += " |";
      md += "\n";
      continue;
    }
    md += " " + RatioCell(p.eta.mean, p.load.mean, p.load, "%.1f") + " | " +
          RatioCell(p.truth_eta.mean, p.truth_load.mean, p.load, "%.1f") + " | " +
          Cell(1e3 * p.net.mean, "%.3f") + " | " + Cell(1e3 * p.truth_net.mean, "%.3f") +
          " | " + RatioCell(p.power_rmse_pct_peak, p.truth_load.mean, p.load, "%.1f") +
          " | " + (p.stiffness.n ? Cell(p.stiffness.mean) : std::string("–")) + " | " +
          Cell(r.result.truth.stiffness) + " | " +
          (p.damping.n ? Cell(p.damping.mean) : std::string("–")) + " | " +
          Cell(r.result.truth.damping) + " |\n";
  }

  // Heatmaps: x × y with the other axes at their first value.
  int failed = 0;
  for (const auto& map : grid.maps) {
    const std::size_t x = Index(map[0]), y = Index(map[1]);
    const std::string name =
        "map_" + std::string(kAxes[x].key) + "__" + std::string(kAxes[y].key);
    std::string dat = "# ix iy x y eta_pct truth_eta_pct net_mJ truth_net_mJ\n";
    std::array<std::size_t, kSweepAxes> digit{};
    const auto sizes = grid.Sizes();
    for (std::size_t ix = 0; ix < sizes[x]; ++ix) {
      for (std::size_t iy = 0; iy < sizes[y]; ++iy) {
        digit[x] = ix;
        digit[y] = iy;
        std::size_t index = 0;
        for (std::size_t a = 0; a < kSweepAxes; ++a) index = index * sizes[a] + digit[a];
        const sim::AmplitudePoint& p = rows[index].point;
        dat += std::to_string(ix) + " " + std::to_string(iy) + " " +
               Exact(grid.values[x][ix]) + " " + Exact(grid.values[y][iy]) + " " +
               Exact(p.eta.mean) + " " + Exact(p.truth_eta.mean) + " " +
               Exact(1e3 * p.net.mean) + " " + Exact(1e3 * p.truth_net.mean) + "\n";
      }
    }
    host::ReplaceFile(out / (name + ".dat"), dat);
    const auto tics = [&](std::size_t axis) {
      std::string t = "(";
      for (std::size_t i = 0; i < grid.values[axis].size(); ++i) {
        t += (i ? ", \"" : "\"") + Num(grid.values[axis][i]) + "\" " + std::to_string(i);
      }
      return t + ")";
    };
    std::string others;
    for (std::size_t a = 0; a < kSweepAxes; ++a) {
      if (a == x || a == y || grid.values[a].size() < 2) continue;
      others += (others.empty() ? "" : ", ") + std::string(kAxes[a].key) + " = " +
                ValueText(static_cast<SweepAxis>(a), grid.values[a][0]);
    }
    for (const auto& [what, column, label] :
         {std::tuple{"eta", 5, "board η (%)"},
          std::tuple{"work", 7, "board net work (mJ)"}}) {
      const std::string figure = name + "_" + what;
      std::string gp =
          "set terminal pngcairo size 900,700 font ',11'\nset output '" + figure +
          ".png'\nset title \"" + label + " per flexion" +
          (others.empty() ? std::string() : "\\n(" + others + ")") +
          "\" noenhanced\nset xlabel '" + std::string(kAxes[x].key) +
          "' noenhanced\nset ylabel '" + std::string(kAxes[y].key) +
          "' noenhanced\nset xtics " + tics(x) + "\nset ytics " + tics(y) +
          "\nset xrange [-0.5:" + std::to_string(sizes[x]) +
          "-0.5]\nset yrange [-0.5:" + std::to_string(sizes[y]) + "-0.5]\nset cblabel '" +
          label +
          "'\nset palette rgb 33,13,10\nset style fill solid 1.0 noborder\n"
          "plot '" +
          name + ".dat' using 1:2:(0.5):(0.5):" + std::to_string(column) +
          " with boxxyerror lc palette notitle, '' using 1:2:(sprintf('%.3g', "
          "$" +
          std::to_string(column) + ")) with labels notitle\n";
      const fs::path script = out / (figure + ".gp");
      host::ReplaceFile(script, gp);
      std::string why;
      if (!host::RunGnuplot(script, &why)) {
        ++failed;
        std::fprintf(stderr, "mjc-paper: figure %s not made: %s\n", figure.c_str(),
                     why.c_str());
      } else {
        md += "\n![" + std::string(label) + "](" + figure + ".png)\n";
      }
    }
  }
  host::ReplaceFile(out / "sweep.md", md);
  std::fputs(md.c_str(), stdout);
  std::fflush(stdout);
  if (failed) throw std::runtime_error(std::to_string(failed) + " figures not made");
}

}  // namespace

const SweepAxisInfo& AxisInfo(SweepAxis axis) { return kAxes[Index(axis)]; }

SweepGrid ParseSweepGrid(std::string_view text, std::string_view source) {
  json j;
  try {
    j = json::parse(text);
  } catch (const json::parse_error& e) {
    Refuse(source, std::string("not JSON: ") + e.what());
  }
  if (!j.is_object()) Refuse(source, "a grid is a JSON object");
  for (const auto& [key, value] : j.items()) {
    if (std::find(std::begin(kTopKeys), std::end(kTopKeys), key) == std::end(kTopKeys)) {
      Refuse(source, "unknown key '" + key + "' (known: " + Known(kTopKeys) + ")");
    }
  }
  SweepGrid g;
  for (const char* key : {"robot", "subject"}) {
    if (!j.contains(key)) continue;
    if (!j[key].is_string() || j[key].get<std::string>().empty()) {
      Refuse(source, std::string("'") + key +
                         "' must be a parameter set's name or .json path (a non-empty "
                         "string)");
    }
    (std::string_view(key) == "robot" ? g.robot : g.subject) = j[key].get<std::string>();
  }
  if (j.contains("repetitions")) {
    const json& r = j["repetitions"];
    if (!r.is_number_integer() || r.get<std::int64_t>() < kMinRepetitions ||
        r.get<std::int64_t>() > kMaxRepetitions) {
      Refuse(source, "'repetitions' = " + r.dump() + " must be an integer from " +
                         std::to_string(kMinRepetitions) + " to " +
                         std::to_string(kMaxRepetitions) + " (cycles per trial)");
    }
    g.repetitions = r.get<std::uint16_t>();
  }
  if (j.contains("seed")) {
    const json& s = j["seed"];
    if (!s.is_number_unsigned()) {
      Refuse(source, "'seed' = " + s.dump() + " must be an integer from 0 to 2^64 - 1");
    }
    g.seed = s.get<std::uint64_t>();
  }
  if (!j.contains("axes") || !j["axes"].is_object()) {
    Refuse(source, "'axes' must be an object of lists (keys: " + AxisKeys() + ")");
  }
  for (const auto& [key, list] : j["axes"].items()) {
    const auto axis = AxisByKey(key);
    if (!axis)
      Refuse(source, "unknown axis 'axes." + key + "' (known: " + AxisKeys() + ")");
    const SweepAxisInfo& info = kAxes[Index(*axis)];
    const std::string where = "axes." + key;
    if (!list.is_array() || list.empty()) {
      Refuse(source, "'" + where + "' must be a non-empty list of values");
    }
    std::vector<double>& values = g.values[Index(*axis)];
    for (std::size_t i = 0; i < list.size(); ++i) {
      const json& v = list[i];
      const std::string at = where + "[" + std::to_string(i) + "]";
      double x = 0;
      if (*axis == SweepAxis::kModel) {
        const auto name = v.is_string() ? v.get<std::string>() : std::string();
        if (name != kModelNames[0] && name != kModelNames[1]) {
          Refuse(source, "'" + at + "' = " + v.dump() + " is not \"kelvin_voigt\" or " +
                             "\"standard_linear_solid\"");
        }
        x = name == kModelNames[1] ? 1.0 : 0.0;
      } else {
        if (!v.is_number()) {
          Refuse(source, "'" + at + "' = " + v.dump() + " is not a number (" +
                             Num(info.min) + " to " + Num(info.max) + " " +
                             std::string(info.unit) + ")");
        }
        x = v.get<double>();
        if (!(x >= info.min && x <= info.max)) {
          Refuse(source, "'" + at + "' = " + v.dump() + " is outside " + Num(info.min) +
                             " to " + Num(info.max) + " " + std::string(info.unit));
        }
      }
      if (std::find(values.begin(), values.end(), x) != values.end()) {
        Refuse(source, "'" + at + "' = " + v.dump() + " repeats a value of the list");
      }
      values.push_back(x);
    }
  }
  if (j.contains("maps")) {
    const json& maps = j["maps"];
    const std::string shape =
        "'maps' must be a list of [x, y] pairs of two different numeric axes of 'axes'";
    if (!maps.is_array() || maps.empty()) Refuse(source, shape);
    for (std::size_t i = 0; i < maps.size(); ++i) {
      const json& m = maps[i];
      if (!m.is_array() || m.size() != 2 || !m[0].is_string() || !m[1].is_string()) {
        Refuse(source, shape + " (maps[" + std::to_string(i) + "] = " + m.dump() + ")");
      }
      std::array<SweepAxis, 2> pair{};
      for (std::size_t k = 0; k < 2; ++k) {
        const std::string key = m[k].get<std::string>();
        const auto axis = AxisByKey(key);
        if (!axis || *axis == SweepAxis::kModel || g.values[Index(*axis)].empty()) {
          Refuse(source, "'maps[" + std::to_string(i) + "]' names '" + key +
                             "', not a numeric axis listed in 'axes'");
        }
        pair[k] = *axis;
      }
      if (pair[0] == pair[1]) {
        Refuse(source, "'maps[" + std::to_string(i) + "]' names one axis twice");
      }
      g.maps.push_back(pair);
    }
  }
  return g;
}

SweepPlan PlanSweep(const SweepGrid& grid, const SweepSettings& settings) {
  SweepPlan plan;
  plan.grid = grid;
  plan.settings = settings;
  plan.robot = Load(grid.robot);
  plan.subject = Load(grid.subject);
  plan.robot.integration.max_step_s = settings.max_step_us * 1e-6;
  if (!settings.noise) {
    plan.robot.sensors.joint_noise_counts = 0;
    plan.robot.sensors.motor_noise_counts = 0;
  }
  plant::ValidatePlantParams(plan.robot, "--max-step-us");
  plan.config = app::DefaultJointConfig();
  if (settings.velocity_window != 0) {
    plan.config.velocity_window = static_cast<std::uint16_t>(settings.velocity_window);
    // The board keeps its own window when it refuses one (even, out of range): every
    // point would then run with another window than the grid's digest says.
    sim::BusBoard board(plan.robot, plan.config);
    if (board.app().control().config().velocity_window != plan.config.velocity_window) {
      throw std::runtime_error("the board refused --velocity-window " +
                               std::to_string(settings.velocity_window) +
                               " (odd, 33 to 1001 ticks)");
    }
  }
  // Absent axes take the base sets' values (the paper's 25° at 0.5 Hz for the trial).
  const plant::InterfaceParams& base = plan.subject.interface;
  const plant::CableParams& cable = plan.robot.cable;
  const double defaults[kSweepAxes] = {
      base.stiffness_Nm_per_rad,
      base.damping_Nm_s_per_rad,
      base.model == plant::InterfaceModel::kStandardLinearSolid ? 1.0 : 0.0,
      base.maxwell_stiffness_Nm_per_rad,
      base.preload_Nm,
      25.0,
      sim::kPaperFrequencyHz,
      plan.robot.sea.spring_rate_N_per_m,
      (cable.c_right_rad - cable.c_left_rad) * kDeg};
  std::array<std::size_t, kSweepAxes> sizes{};
  for (std::size_t a = 0; a < kSweepAxes; ++a) {
    plan.values[a] =
        grid.values[a].empty() ? std::vector<double>{defaults[a]} : grid.values[a];
    sizes[a] = plan.values[a].size();
  }
  // Robot variants: the spring rate and the slack (about the base dead band's centre).
  const std::size_t springs = sizes[Index(SweepAxis::kSpringRate)];
  const std::size_t slacks = sizes[Index(SweepAxis::kCableSlack)];
  const double centre = 0.5 * (cable.c_right_rad + cable.c_left_rad);
  for (std::size_t s = 0; s < springs; ++s) {
    for (std::size_t l = 0; l < slacks; ++l) {
      plant::PlantParams v = plan.robot;
      v.interface = {};
      v.sea.spring_rate_N_per_m = plan.values[Index(SweepAxis::kSpringRate)][s];
      const double half = 0.5 * plan.values[Index(SweepAxis::kCableSlack)][l] / kDeg;
      v.cable.c_right_rad = centre + half;
      v.cable.c_left_rad = centre - half;
      plant::ValidatePlantParams(v,
                                 "robot variant " + std::to_string(plan.variants.size()));
      plan.variants.push_back(v);
    }
  }
  // A bound before anything is built: the product of nine lists grows fast, and each
  // point costs a trial (~0.1 s of a core) and two files.
  std::size_t total = 1;
  for (const std::size_t n : sizes) {
    total *= n;
    if (total > kMaxPoints) {
      throw std::runtime_error("the grid has more than " + std::to_string(kMaxPoints) +
                               " points (the product of its axes' lengths): split it");
    }
  }
  for (std::size_t i = 0; i < total; ++i) {
    const auto d = Digits(i, sizes);
    SweepPoint p;
    p.index = i;
    for (std::size_t a = 0; a < kSweepAxes; ++a) p.value[a] = plan.values[a][d[a]];
    p.variant =
        d[Index(SweepAxis::kSpringRate)] * slacks + d[Index(SweepAxis::kCableSlack)];
    p.interface.present = true;
    p.interface.model = p.value[Index(SweepAxis::kModel)] > 0.5
                            ? plant::InterfaceModel::kStandardLinearSolid
                            : plant::InterfaceModel::kKelvinVoigt;
    p.interface.stiffness_Nm_per_rad = p.value[Index(SweepAxis::kStiffness)];
    p.interface.damping_Nm_s_per_rad = p.value[Index(SweepAxis::kDamping)];
    p.interface.maxwell_stiffness_Nm_per_rad =
        p.value[Index(SweepAxis::kMaxwellStiffness)];
    p.interface.preload_Nm = p.value[Index(SweepAxis::kPreload)];
    plant::PlantParams check = plan.variants[p.variant];
    check.interface = p.interface;
    plant::ValidatePlantParams(check, "grid point " + std::to_string(i) + " (" +
                                          PointAxes(plan.values, p.value) + ")");
    plan.points.push_back(p);
  }
  // The digest: the grid as parsed (defaults filled), the settings and the base sets.
  json maps = json::array();
  for (const auto& m : grid.maps) {
    maps.push_back(
        {std::string(kAxes[Index(m[0])].key), std::string(kAxes[Index(m[1])].key)});
  }
  const json resolved = ResolvedJson(plan.values);
  const json material = {{"resolved", resolved},
                         {"repetitions", grid.repetitions},
                         {"seed", grid.seed},
                         {"maps", maps},
                         {"noise", settings.noise},
                         {"max_step_us", settings.max_step_us},
                         {"velocity_window", settings.velocity_window},
                         {"robot", plant::PlantParamsToJson(plan.robot)},
                         {"subject", plant::PlantParamsToJson(plan.subject)}};
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx",
                static_cast<unsigned long long>(Fnv1a64(material.dump())));
  plan.digest = hex;
  plan.record = {{"digest", plan.digest},
                 {"points", total},
                 {"repetitions", grid.repetitions},
                 {"seed", grid.seed},
                 {"robot", grid.robot},
                 {"subject", grid.subject},
                 {"maps", maps},
                 {"resolved", resolved},
                 {"settings",
                  {{"noise", settings.noise},
                   {"max_step_us", settings.max_step_us},
                   {"velocity_window", settings.velocity_window}}}};
  return plan;
}

std::optional<Shard> ParseShard(std::string_view text, std::string* why) {
  const std::size_t slash = text.find('/');
  const auto number = [](std::string_view s, std::size_t* v) {
    if (s.empty() || s.size() > 9) return false;
    *v = 0;
    for (const char c : s) {
      if (c < '0' || c > '9') return false;
      *v = *v * 10 + static_cast<std::size_t>(c - '0');
    }
    return true;
  };
  Shard s;
  if (slash == std::string_view::npos || !number(text.substr(0, slash), &s.index) ||
      !number(text.substr(slash + 1), &s.count)) {
    *why =
        "--shard '" + std::string(text) + "' is not i/n (two whole numbers, 0 <= i < n)";
    return std::nullopt;
  }
  if (s.count == 0 || s.index >= s.count) {
    *why = "--shard " + std::string(text) +
           ": the index must be 0 to n - 1 and n at least 1";
    return std::nullopt;
  }
  return s;
}

std::optional<SweepPointResult> ReadSweepPoint(const fs::path& out, std::size_t index) {
  return ReadPoint(out, index, "");
}

namespace {

// grid.json in `out`: written when absent; refused when it is another grid's.
void ClaimFolder(const fs::path& out, const std::string& digest, const json& record) {
  fs::create_directories(out / "points");
  const fs::path path = out / "grid.json";
  if (fs::exists(path)) {
    const Resolved held = ReadResolved(out);
    if (held.digest != digest) {
      throw std::runtime_error(out.string() + " holds a sweep of another grid (digest " +
                               held.digest + ", this one " + digest +
                               "): give another --out");
    }
    return;
  }
  host::ReplaceFile(path, record.dump(2) + "\n");
}

std::string Duration(double s) {
  if (s < 10) return Fixed("%.1f s", s);
  if (s < 120) return Fixed("%.0f s", s);
  if (s < 7200) return Fixed("%.1f min", s / 60);
  return Fixed("%.1f h", s / 3600);
}

// Calibrates each of `variants` on a board of its own (the paper's sweep and fit, the
// record uploaded), on up to `threads` threads; the records by variant.
std::map<std::size_t, Calibration> Calibrate(const SweepPlan& plan,
                                             const std::vector<std::size_t>& variants,
                                             int threads) {
  std::vector<Calibration> records(variants.size());
  std::vector<std::string> errors(variants.size());
  std::atomic<std::size_t> next{0};
  const auto work = [&] {
    for (std::size_t i = next++; i < variants.size(); i = next++) {
      try {
        plant::PlantParams robot = plan.variants[variants[i]];
        robot.sensors.noise_seed = Seed(plan.grid.seed, 2, variants[i]);
        // The designer knows what was built: the board is told the variant's joint
        // (its spring rate goes into the record as `mjc calibrate --robot` puts it).
        host::RobotDescription d;
        d.name = "variant" + std::to_string(variants[i]);
        d.joint_pulley_radius_m = robot.sea.joint_pulley_radius_m;
        d.motor_pulley_radius_m = robot.cable.alpha * robot.sea.joint_pulley_radius_m;
        d.spring_rate_N_per_m = robot.sea.spring_rate_N_per_m;
        d.motor_counts_per_rev = robot.sensors.motor_counts_per_rev;
        d.gear_ratio = robot.motor.gear_ratio;
        d.motor_count_at_zero = robot.sensors.motor_count_at_zero;
        d.joint_zero_count = robot.sensors.joint_zero_count;
        sim::BusBoard board(robot, plan.config);
        const sim::CalibrationOutcome cal =
            sim::RunCalibration(board, sim::PaperCalibrationSweep(), {&d, false});
        if (!cal.uploaded) {
          errors[i] = "robot variant " + std::to_string(variants[i]) + " (spring rate " +
                      Num(robot.sea.spring_rate_N_per_m) + " N/m, slack " +
                      Num((robot.cable.c_right_rad - robot.cable.c_left_rad) * kDeg) +
                      "°) was not calibrated: " + cal.message;
        }
        records[i] = cal.record;
      } catch (const std::exception& e) {
        errors[i] = e.what();
      }
    }
  };
  if (threads <= 0) threads = static_cast<int>(std::thread::hardware_concurrency());
  const std::size_t workers =
      std::clamp<std::size_t>(static_cast<std::size_t>(std::max(threads, 1)), 1,
                              std::max<std::size_t>(variants.size(), 1));
  std::vector<std::thread> pool;
  for (std::size_t w = 1; w < workers; ++w) pool.emplace_back(work);
  work();
  for (std::thread& t : pool) t.join();
  for (const std::string& e : errors) {
    if (!e.empty()) throw std::runtime_error(e);
  }
  std::map<std::size_t, Calibration> out;
  for (std::size_t i = 0; i < variants.size(); ++i) out[variants[i]] = records[i];
  return out;
}

}  // namespace

int RunSweep(const SweepPlan& plan, const SweepRunOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  ClaimFolder(options.out, plan.digest, plan.record);
  const Resolved grid = ReadResolved(options.out);
  std::vector<const SweepPoint*> todo;
  std::size_t mine = 0, resumed = 0;
  for (const SweepPoint& p : plan.points) {
    if (p.index % options.shard.count != options.shard.index) continue;
    ++mine;
    if (ReadPoint(options.out, p.index, plan.digest)) {
      ++resumed;
    } else {
      todo.push_back(&p);
    }
  }
  const std::string shard_text = options.shard.count > 1
                                     ? ", shard " + std::to_string(options.shard.index) +
                                           "/" + std::to_string(options.shard.count) +
                                           ": " + std::to_string(mine)
                                     : "";
  std::fprintf(stderr, "sweep %s: %zu grid points%s, %zu resumed from %s, %zu to run\n",
               plan.digest.c_str(), plan.points.size(), shard_text.c_str(), resumed,
               options.out.string().c_str(), todo.size());

  std::size_t calibrations = 0;
  if (!todo.empty()) {
    std::set<std::size_t> needed;
    for (const SweepPoint* p : todo) needed.insert(p->variant);
    if (!options.quiet) {
      std::fprintf(stderr, "calibrating %zu robot variant(s)\n", needed.size());
    }
    calibrations = needed.size();
    const std::map<std::size_t, Calibration> records =
        Calibrate(plan, {needed.begin(), needed.end()}, options.threads);
    std::vector<sim::TrialSpec> specs;
    for (const SweepPoint* p : todo) {
      sim::TrialSpec spec;
      spec.interface = p->interface;
      spec.amplitude_deg = p->value[Index(SweepAxis::kAmplitude)];
      spec.frequency_hz = p->value[Index(SweepAxis::kFrequency)];
      spec.noise_seed = Seed(plan.grid.seed, 1, p->index);
      spec.repetitions = plan.grid.repetitions;
      spec.robot = &plan.variants[p->variant];
      spec.record = &records.at(p->variant);
      spec.label =
          "point " + std::to_string(p->index) + ": " + PointAxes(plan.values, p->value);
      specs.push_back(std::move(spec));
    }
    const auto trials_start = std::chrono::steady_clock::now();
    std::size_t finished = 0;
    (void)sim::RunTrials(
        plan.robot, plan.config, records.begin()->second, specs, options.threads,
        [&](const std::string& label, double) {
          ++finished;
          if (options.quiet) return;
          const double elapsed = std::chrono::duration<double>(
                                     std::chrono::steady_clock::now() - trials_start)
                                     .count();
          const double left = elapsed / static_cast<double>(finished) *
                              static_cast<double>(specs.size() - finished);
          std::fprintf(
              stderr, "[%3.0f%%] %zu/%zu %s (%s, ETA %s)\n",
              100.0 * static_cast<double>(resumed + finished) / static_cast<double>(mine),
              resumed + finished, mine, label.c_str(), Duration(elapsed).c_str(),
              Duration(left).c_str());
        },
        nullptr,
        [&](std::size_t i, const sim::TrialOutcome& trial) {
          WritePoint(options.out, grid, *todo[i], specs[i].noise_seed, trial);
        });
  }
  const double wall =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (!todo.empty()) {
    const unsigned threads = options.threads > 0 ? static_cast<unsigned>(options.threads)
                                                 : std::thread::hardware_concurrency();
    // The calibrations of the robot variants are in the wall time: a sweep pays them.
    std::fprintf(stderr,
                 "sweep: %zu trials (and %zu calibrations) in %.2f s on %u threads (%.3f "
                 "trials/s)\n",
                 todo.size(), calibrations, wall, threads,
                 static_cast<double>(todo.size()) / wall);
  }
  if (options.shard.count > 1) {
    std::fprintf(stderr,
                 "shard %zu/%zu complete in %s: join the shards' folders with "
                 "--scenario sweep --merge DIR... --out DIR\n",
                 options.shard.index, options.shard.count, options.out.string().c_str());
    return 0;
  }
  WriteSummary(options.out, grid);
  return 0;
}

int MergeSweeps(const std::vector<fs::path>& shards, const fs::path& out, bool quiet) {
  if (shards.empty()) throw std::runtime_error("--merge needs the shards' folders");
  std::vector<Resolved> grids;
  for (const fs::path& s : shards) grids.push_back(ReadResolved(s));
  for (std::size_t i = 1; i < grids.size(); ++i) {
    if (grids[i].digest != grids[0].digest) {
      throw std::runtime_error("the shards' grids differ: " + shards[0].string() +
                               " holds grid " + grids[0].digest + ", " +
                               shards[i].string() + " grid " + grids[i].digest);
    }
  }
  const Resolved& grid = grids[0];
  std::vector<std::size_t> from(grid.points, shards.size());
  std::vector<std::size_t> missing;
  for (std::size_t p = 0; p < grid.points; ++p) {
    for (std::size_t s = 0; s < shards.size() && from[p] == shards.size(); ++s) {
      if (ReadPoint(shards[s], p, grid.digest)) from[p] = s;
    }
    if (from[p] == shards.size()) missing.push_back(p);
  }
  if (!missing.empty()) {
    std::string list;
    for (std::size_t k = 0; k < missing.size() && k < 20; ++k) {
      list += (k ? ", " : "") + std::to_string(missing[k]);
    }
    if (missing.size() > 20) list += ", ...";
    throw std::runtime_error(
        std::to_string(missing.size()) + " of " + std::to_string(grid.points) +
        " points are in none of the folders (" + list + "): run their shards first");
  }
  const auto record = host::ReadFileText(shards[0] / "grid.json");
  ClaimFolder(out, grid.digest, json::parse(*record));
  for (std::size_t p = 0; p < grid.points; ++p) {
    const fs::path& src = shards[from[p]];
    if (fs::exists(out) && fs::equivalent(src, out)) continue;
    for (const char* ext : {"csv", "json"}) {
      host::ReplaceFile(PointPath(out, p, ext),
                        *host::ReadFileText(PointPath(src, p, ext)));
    }
  }
  if (!quiet)
    std::fprintf(stderr, "merged %zu points of grid %s from %zu folders into %s\n",
                 grid.points, grid.digest.c_str(), shards.size(), out.string().c_str());
  WriteSummary(out, grid);
  return 0;
}

int SweepMain(const SweepCommand& command) {
  try {
    if (!command.merge.empty()) {
      if (!command.grid_path.empty() || !command.shard.empty()) {
        std::fprintf(
            stderr,
            "mjc-paper: --merge takes the shards' folders, not --grid or --shard\n");
        return 2;
      }
      std::vector<fs::path> shards(command.merge.begin(), command.merge.end());
      return MergeSweeps(shards, command.out, command.quiet);
    }
    if (command.grid_path.empty()) {
      std::fprintf(stderr,
                   "mjc-paper: --scenario sweep needs --grid FILE (or --merge DIR...)\n");
      return 2;
    }
    SweepRunOptions options;
    options.out = command.out;
    options.threads = command.threads;
    options.quiet = command.quiet;
    if (!command.shard.empty()) {
      std::string why;
      const auto shard = ParseShard(command.shard, &why);
      if (!shard) {
        std::fprintf(stderr, "mjc-paper: %s\n", why.c_str());
        return 2;
      }
      options.shard = *shard;
    }
    const auto text = host::ReadFileText(command.grid_path);
    if (!text) {
      std::fprintf(stderr, "mjc-paper: %s: cannot be read\n", command.grid_path.c_str());
      return 2;
    }
    SweepPlan plan;
    try {
      plan = PlanSweep(ParseSweepGrid(*text, command.grid_path), command.settings);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "mjc-paper: %s\n", e.what());
      return 2;
    }
    return RunSweep(plan, options);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "mjc-paper: %s\n", e.what());
    return 1;
  }
}

}  // namespace mjc::paper
