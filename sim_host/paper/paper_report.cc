#include "paper_report.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <numbers>
#include <random>
#include <stdexcept>

#include "mjc/host/calibration_io.h"
#include "mjc/host/joint_limits.h"
#include "mjc/host/report.h"
#include "mjc/host/units.h"

namespace mjc::paper {
namespace {

namespace fs = std::filesystem;
using host::CsvTable;
constexpr double kMilli = 1e3;

std::string Format(const char* fmt, double a) {
  char text[64];
  std::snprintf(text, sizeof text, fmt, a);
  return text;
}

std::string PlusMinus(const host::Stats& s, double scale, const char* fmt, bool se) {
  return Format(fmt, s.mean * scale) + " ± " + Format(fmt, (se ? s.se : s.std) * scale);
}

nlohmann::json StatsJson(const host::Stats& s) {
  return {{"n", s.n}, {"mean", s.mean}, {"std", s.std}, {"se", s.se}};
}

// The sensor-noise seed of the run at `index` in the list: every run has a board of
// its own and needs a noise sequence of its own. std::seed_seq's mixing is specified
// by the standard, so the same on every library.
std::uint64_t RunSeed(std::uint64_t seed, std::size_t index) {
  std::seed_seq mix{static_cast<std::uint32_t>(seed),
                    static_cast<std::uint32_t>(seed >> 32),
                    static_cast<std::uint32_t>(index)};
  std::uint32_t words[2];
  mix.generate(std::begin(words), std::end(words));
  return (std::uint64_t{words[0]} << 32) | words[1];
}

// Relative error of a board window energy against truth, in % of |truth load|.
double WindowEnergyErrorPct(const sim::WindowOutcome& w) {
  const double scale = std::fabs(w.truth_load);
  if (scale == 0) return 0;
  const double e1 = std::fabs(w.load - w.truth_load);
  const double e2 = std::fabs(w.unload - w.truth_unload);
  return 100.0 * std::max(e1, e2) / scale;
}

// Tables II–III's errors across amplitudes for one subject: RMSE (J) and NRMSE (%) of
// the loading, unloading and net work, of the board against the plant's truth
// (sim::SubjectSweep) or against the model's prediction (sim::ModelComparison), with
// the reference's ranges and the noise floor they were judged against.
struct SweepErrors {
  std::string subject;
  double rmse_load, rmse_unload, rmse_net, nrmse_load, nrmse_unload, nrmse_net;
  double range_load, range_unload, range_net, noise_floor;
};

template <typename Compared>
SweepErrors ErrorsOf(const Compared& c) {
  return {c.subject,      c.rmse_load,    c.rmse_unload,  c.rmse_net,
          c.nrmse_load,   c.nrmse_unload, c.nrmse_net,    c.range_load,
          c.range_unload, c.range_net,    c.noise_floor_J};
}

// A normalised error as a table prints it: the percentage, or, when the reference's
// range was within the noise (sim::EnergyNoiseFloor), why there is none.
std::string NrmseCell(double pct, double range_J, double floor_J) {
  if (std::isfinite(pct)) return Format("%.2f%%", pct);
  return "n/a (range " + Format("%.4f", range_J * kMilli) +
         " mJ, within the noise floor " + Format("%.4f", floor_J * kMilli) + " mJ)";
}

// A board's or the truth's η beside the loading work it divides by: n/a, with the
// reason, when that work is at or below the floor (no ratio worth taking), or when a
// window of the point had no η at all.
std::string EtaCell(const host::Stats& eta, double load_J, double floor_J,
                    const char* format) {
  if (!std::isfinite(eta.mean)) return "n/a (a window without loading work)";
  if (load_J <= floor_J) {
    return "n/a (loading " + Format("%.4f", load_J * kMilli) +
           " mJ, within the noise floor " + Format("%.4f", floor_J * kMilli) + " mJ)";
  }
  return Format(format, eta.mean);
}

// The "rmse_J", "nrmse_pct" (null where not judged), "range_J" and "noise_floor_J"
// members of a subject's entry in results.json.
void AddErrorsJson(const SweepErrors& e, nlohmann::json* subject) {
  auto judged = [](double pct) {
    return std::isfinite(pct) ? nlohmann::json(pct) : nlohmann::json(nullptr);
  };
  (*subject)["rmse_J"] = {
      {"load", e.rmse_load}, {"unload", e.rmse_unload}, {"net", e.rmse_net}};
  (*subject)["nrmse_pct"] = {{"load", judged(e.nrmse_load)},
                             {"unload", judged(e.nrmse_unload)},
                             {"net", judged(e.nrmse_net)}};
  (*subject)["range_J"] = {
      {"load", e.range_load}, {"unload", e.range_unload}, {"net", e.range_net}};
  (*subject)["noise_floor_J"] = e.noise_floor;
}

// The table's header and one row per subject, in Markdown; the same rows to `csv`
// (an NRMSE not judged is nan there, beside the ranges and the floor).
std::string ErrorTable(const std::vector<SweepErrors>& rows, const fs::path& csv) {
  std::string text =
      "| subject | RMSE loading (mJ) | RMSE unloading (mJ) | RMSE net (mJ) | NRMSE "
      "loading | NRMSE unloading | NRMSE net |\n|---|---|---|---|---|---|---|\n";
  CsvTable table({"subject", "rmse_load_mJ", "rmse_unload_mJ", "rmse_net_mJ",
                  "nrmse_load_pct", "nrmse_unload_pct", "nrmse_net_pct", "range_load_mJ",
                  "range_unload_mJ", "range_net_mJ", "noise_floor_mJ"});
  for (const SweepErrors& e : rows) {
    text += "| " + e.subject + " | " + Format("%.4f", e.rmse_load * kMilli) + " | " +
            Format("%.4f", e.rmse_unload * kMilli) + " | " +
            Format("%.4f", e.rmse_net * kMilli) + " | " +
            NrmseCell(e.nrmse_load, e.range_load, e.noise_floor) + " | " +
            NrmseCell(e.nrmse_unload, e.range_unload, e.noise_floor) + " | " +
            NrmseCell(e.nrmse_net, e.range_net, e.noise_floor) + " |\n";
    table.AddRow({e.subject, CsvTable::Number(e.rmse_load * kMilli),
                  CsvTable::Number(e.rmse_unload * kMilli),
                  CsvTable::Number(e.rmse_net * kMilli), CsvTable::Number(e.nrmse_load),
                  CsvTable::Number(e.nrmse_unload), CsvTable::Number(e.nrmse_net),
                  CsvTable::Number(e.range_load * kMilli),
                  CsvTable::Number(e.range_unload * kMilli),
                  CsvTable::Number(e.range_net * kMilli),
                  CsvTable::Number(e.noise_floor * kMilli)});
  }
  table.Write(csv);
  return text;
}

// Figs. 10–12's work per flexion at one amplitude as both of their tables show it (the
// amplitude sweep's and the model comparison's): the board's loading, unloading and
// net work (mean ± SE) each beside a reference's, the plant's truth or the model's
// prediction (J).
struct WorkPoint {
  double amplitude_deg;
  const host::Stats& load;
  const host::Stats& unload;
  const host::Stats& net;
  double reference_load, reference_unload, reference_net;
};

// Its Markdown cells, "| amplitude | … | reference net", for the caller to close.
std::string WorkCells(const WorkPoint& p) {
  return "| " + Format("%.0f°", p.amplitude_deg) + " | " +
         PlusMinus(p.load, kMilli, "%.3f", true) + " | " +
         Format("%.3f", p.reference_load * kMilli) + " | " +
         PlusMinus(p.unload, kMilli, "%.3f", true) + " | " +
         Format("%.3f", p.reference_unload * kMilli) + " | " +
         PlusMinus(p.net, kMilli, "%.3f", true) + " | " +
         Format("%.3f", p.reference_net * kMilli);
}

// Its CSV cells: subject, amplitude, then each work's mean, SE and reference (mJ).
std::vector<std::string> WorkCsvCells(const std::string& subject, const WorkPoint& p) {
  return {subject,
          CsvTable::Number(p.amplitude_deg),
          CsvTable::Number(p.load.mean * kMilli),
          CsvTable::Number(p.load.se * kMilli),
          CsvTable::Number(p.reference_load * kMilli),
          CsvTable::Number(p.unload.mean * kMilli),
          CsvTable::Number(p.unload.se * kMilli),
          CsvTable::Number(p.reference_unload * kMilli),
          CsvTable::Number(p.net.mean * kMilli),
          CsvTable::Number(p.net.se * kMilli),
          CsvTable::Number(p.reference_net * kMilli)};
}

// Its entry's members in results.json that both tables have: the amplitude and the
// board's statistics (the reference's are named by each table).
nlohmann::json WorkJson(const WorkPoint& p) {
  return {{"amplitude_deg", p.amplitude_deg},
          {"load_J", StatsJson(p.load)},
          {"unload_J", StatsJson(p.unload)},
          {"net_J", StatsJson(p.net)}};
}

// The amplitude sweep's motor-pulley amplitudes (the largest, with the calibration
// sweep's, bounds the joint's travel: TravelRefusal).
const std::vector<double> kAmplitudesDeg = {6, 8, 11, 15, 20, 25};

// The bound the default joint's windows are held to against the plant's truth
// (tests/sim/paper_scenarios_test.cc): loading and unloading within 2 % of the loading
// work. Beyond it on a described joint, the description is suspect.
constexpr double kWindowEnergyBoundPct = 2.0;

// A fitted α this far from the description's (relative) is not the described cable:
// the free fit finds the example joint's α within 0.8 %.
constexpr double kAlphaMismatch = 0.02;

}  // namespace

std::string TravelRefusal(const host::RobotDescription& robot) {
  const host::JointTravel travel{host::DegToRad(robot.extension_limit_deg),
                                 host::DegToRad(robot.flexion_limit_deg), robot.Alpha()};
  const double sweep_deg =
      host::RadToDeg(sim::PaperCalibrationSweep().end_amplitude.ToDouble());
  for (const double a : {sweep_deg, kAmplitudesDeg.back()}) {
    const std::string why = host::TravelViolation(a, travel);
    if (!why.empty()) return robot.name + ": the paper's motion of " + why;
  }
  return "";
}

Report::Report(fs::path out, bool quiet, double frequency_hz)
    : out_(std::move(out)), quiet_(quiet), frequency_hz_(frequency_hz) {
  fs::create_directories(out_);
}

void Report::Progress(const std::string& stage, double fraction) {
  if (quiet_) return;
  std::fprintf(stderr, "[%3.0f%%] %s\n", 100.0 * std::clamp(fraction, 0.0, 1.0),
               stage.c_str());
}

void Report::Print(const std::string& text) {
  std::fputs(text.c_str(), stdout);
  std::fflush(stdout);
  tables_ += text;
}

void Report::Warn(const std::string& text) {
  std::fprintf(stderr, "mjc-paper: warning: %s\n", text.c_str());
  tables_ += "\n**warning**: " + text + "\n";
  json_["warnings"].push_back(text);
}

void Report::Robot(const Joint& joint, const plant::PlantParams& plant) {
  Print("\n## Joint\n\n");
  if (!joint.robot) {
    Print(
        "no robot description (--robot-description): the board assumes the default "
        "joint (α = 1, its own stiffness and joint zero)\n");
    json_["robot"] = nullptr;
    return;
  }
  described_ = true;
  const host::RobotDescription& d = *joint.robot;
  Print("robot " + host::DescribeRobot(d, joint.path) + "\n\n");
  // The simulator's privilege: the description against the plant it runs on.
  Print("| | description | plant |\n|---|---|---|\n");
  nlohmann::json differ = nlohmann::json::array();
  const auto row = [&](const char* what, const char* fmt, double described, double truth,
                       double tolerance) {
    const bool same = std::fabs(described - truth) <= tolerance;
    Print(std::string("| ") + what + " | " + Format(fmt, described) + " | " +
          Format(fmt, truth) + (same ? "" : " (differs)") + " |\n");
    if (!same) differ.push_back(what);
  };
  row("α = r_m/r_j", "%.4f", d.Alpha(), plant.cable.alpha, 1e-9);
  row("spring rate k (N/m)", "%.1f", d.spring_rate_N_per_m, plant.sea.spring_rate_N_per_m,
      1e-9);
  row("SEA stiffness K (N·m/rad)", "%.4f", d.SeaStiffness(), plant.sea.Stiffness(), 1e-9);
  row("joint zero (count)", "%.0f", d.joint_zero_count, plant.sensors.joint_zero_count,
      0);
  row("motor count at zero", "%.0f", d.motor_count_at_zero,
      plant.sensors.motor_count_at_zero, 0);
  if (d.cable_friction_Nm > 0) {
    row("cable friction (N·m)", "%.3f", d.cable_friction_Nm, plant.cable.coulomb_Nm,
        1e-9);
  }
  json_["robot"] = joint.record;
  json_["robot"]["plant_differs"] = differ;
  if (!differ.empty()) {
    std::string what;
    for (const auto& w : differ)
      what += (what.empty() ? "" : ", ") + w.get<std::string>();
    Warn("the description of " + d.name + " is not the plant's joint (" + what +
         "): the board's numbers follow the description, the truth the plant");
  }
}

void Report::Check(const JointCheck& c) {
  const double deg = 180.0 / std::numbers::pi;
  Print("\ncalibration against the described α " + Format("%.4f", c.described_alpha) +
        ": fit rms " + Format("%.3f", c.fixed_rms_rad * deg) +
        "°; refitted with α free (±" + Format("%.0f", 100 * host::kAlphaFitSpan) +
        " %): ");
  nlohmann::json json = {{"described_alpha", c.described_alpha},
                         {"fixed_rms_rad", c.fixed_rms_rad},
                         {"free_fitted", c.free_fitted}};
  if (c.free_fitted) {
    const double off = c.free_alpha / c.described_alpha - 1.0;
    Print("α " + Format("%.4f", c.free_alpha) + " (" + Format("%+.1f", 100 * off) +
          " %), rms " + Format("%.3f", c.free_rms_rad * deg) + "°\n");
    json["free_alpha"] = c.free_alpha;
    json["free_rms_rad"] = c.free_rms_rad;
    if (std::fabs(off) > kAlphaMismatch) {
      Warn("the calibration sweep fits α " + Format("%.4f", c.free_alpha) + ", " +
           Format("%+.1f", 100 * off) + " % off the described " +
           Format("%.4f", c.described_alpha) + " (rms " +
           Format("%.3f", c.fixed_rms_rad * deg) + "° against " +
           Format("%.3f", c.free_rms_rad * deg) +
           "°): the cable is not the described one");
    }
  } else {
    Print("refused: " + c.free_message + "\n");
    json["free_message"] = c.free_message;
    Warn("the calibration sweep does not fit α within ±" +
         Format("%.0f", 100 * host::kAlphaFitSpan) + " % of the described " +
         Format("%.4f", c.described_alpha) + " (" + c.free_message +
         "): the cable is not the described one");
  }
  Print(
      "(the calibration runs on the robot alone: its spring carries almost no torque, "
      "so a wrong spring rate k is not visible to it; the window energies follow k as "
      "described)\n");
  json_["joint_check"] = json;
}

void Report::Figure(const std::string& name, const std::string& script) {
  const fs::path path = out_ / (name + ".gp");
  std::ofstream(path) << "set terminal pngcairo size 900,600 font ',11'\nset output '"
                      << name << ".png'\nset grid\nset key top left\n"
                      << script;
  std::string why;
  if (host::RunGnuplot(path, &why)) {
    figures_.push_back(name + ".png");
  } else {
    ++failed_figures_;
    std::fprintf(stderr, "mjc-paper: figure %s not made: %s\n", name.c_str(),
                 why.c_str());
  }
}

void Report::Calibration(const sim::CalibrationOutcome& cal) {
  const double deg = 180.0 / std::numbers::pi;
  Print(
      "\n## Calibration (Fig. 7): increasing sinusoid on the robot alone, NLopt fit\n\n");
  Print("| offset | plant (°) | fitted (°) | error (°) |\n|---|---|---|---|\n");
  Print("| c_r | " + Format("%.4f", cal.true_c_right_rad * deg) + " | " +
        Format("%.4f", cal.fit.c_right_rad * deg) + " | " +
        Format("%+.4f", cal.error_right_deg) + " |\n");
  Print("| c_l | " + Format("%.4f", cal.true_c_left_rad * deg) + " | " +
        Format("%.4f", cal.fit.c_left_rad * deg) + " | " +
        Format("%+.4f", cal.error_left_deg) + " |\n\n");
  Print("fit: " + std::string(host::ToString(cal.fit.status)) + ", rms " +
        Format("%.3f", cal.fit.rms_error_rad * deg) + "°, joint lag " +
        Format("%.2f", cal.fit.lag_s * 1e3) + " ms, " +
        Format("%.1f", cal.fit.elapsed_ms) + " ms, " +
        std::to_string(cal.fit.evaluations) + " evaluations; " + cal.message + "\n");

  CsvTable csv({"motor_rad", "joint_rad"});
  for (std::size_t i = 0; i < cal.motor_rad.size(); ++i) {
    csv.AddRow({CsvTable::Number(cal.motor_rad[i]), CsvTable::Number(cal.joint_rad[i])});
  }
  csv.Write(out_ / "calibration.csv");
  json_["calibration"] = {{"true_c_right_rad", cal.true_c_right_rad},
                          {"true_c_left_rad", cal.true_c_left_rad},
                          {"fit_c_right_rad", cal.fit.c_right_rad},
                          {"fit_c_left_rad", cal.fit.c_left_rad},
                          {"error_right_deg", cal.error_right_deg},
                          {"error_left_deg", cal.error_left_deg},
                          {"rms_error_rad", cal.fit.rms_error_rad},
                          {"joint_lag_s", cal.fit.lag_s},
                          {"fit_ms", cal.fit.elapsed_ms},
                          {"evaluations", cal.fit.evaluations},
                          {"uploaded", cal.uploaded},
                          {"message", cal.message}};
  const double cr = cal.fit.c_right_rad * deg, cl = cal.fit.c_left_rad * deg;
  Figure("fig7_calibration",
         "set title 'Backlash calibration: joint vs motor angle (robot alone)'\n"
         "set xlabel 'motor pulley angle (deg)'\nset ylabel 'joint angle (deg)'\n"
         "set datafile separator ','\nd = 180/pi\n"
         "plot 'calibration.csv' every ::1 using ($1*d):($2*d) with lines lw 1 title "
         "'measured', x - " +
             Format("%.5f", cr) + " with lines dt 2 lw 2 title 'θ_m − c_r (fit)', x - " +
             Format("%.5f", cl) + " with lines dt 3 lw 2 title 'θ_m − c_l (fit)'\n");
}

void Report::Trial(const sim::TrialOutcome& trial, double amplitude_deg) {
  CsvTable csv({"t_s", "setpoint_rad", "motor_rad", "joint_rad", "torque_Nm", "power_W",
                "truth_power_W"});
  for (const auto& r : trial.trace) {
    csv.AddRow({CsvTable::Number(r.t), CsvTable::Number(r.setpoint),
                CsvTable::Number(r.motor), CsvTable::Number(r.joint),
                CsvTable::Number(r.torque), CsvTable::Number(r.power),
                CsvTable::Number(r.truth_power)});
  }
  csv.Write(out_ / "trial_timeseries.csv");
  Figure("fig8_trial",
         "set datafile separator ','\nset multiplot layout 3,1 title 'One trial: " +
             Format("%.0f", amplitude_deg) + "° at " + Format("%g", frequency_hz_) +
             " Hz, five repetitions'\nd = 180/pi\nset ylabel 'angle (deg)'\n"
             "plot 'trial_timeseries.csv' every ::1 using 1:($3*d) with lines title "
             "'motor', "
             "'' every ::1 using 1:($4*d) with lines title 'joint'\n"
             "set ylabel 'torque (N·m)'\nplot 'trial_timeseries.csv' every ::1 using 1:5 "
             "with "
             "lines title 'SEA torque (board)'\n"
             "set ylabel 'power (mW)'\nset xlabel 'time (s)'\n"
             "plot 'trial_timeseries.csv' every ::1 using 1:($6*1000) with lines title "
             "'board "
             "estimate', '' every ::1 using 1:($7*1000) with lines dt 2 title 'plant "
             "truth'\n"
             "unset multiplot\n");
}

void Report::Repeatability(const sim::RepeatabilityOutcome& rep, double amplitude_deg) {
  Print("\n## Table I: energy loss η for the repeatability study (" +
        Format("%.0f", amplitude_deg) + "°, " + Format("%g", frequency_hz_) +
        " Hz, 5 trials × middle 3 of 5 flexions, re-donned)\n\n");
  Print("| | board mean | board std | truth mean | truth std |\n|---|---|---|---|---|\n");
  CsvTable csv({"trial", "repetition", "eta_pct", "truth_eta_pct", "load_J",
                "truth_load_J", "unload_J", "truth_unload_J"});
  nlohmann::json trials = nlohmann::json::array();
  for (std::size_t i = 0; i < rep.eta.size(); ++i) {
    Print("| Trial " + std::to_string(i + 1) + " | " + Format("%.2f%%", rep.eta[i].mean) +
          " | " + Format("%.3f%%", rep.eta[i].std) + " | " +
          Format("%.2f%%", rep.truth_eta[i].mean) + " | " +
          Format("%.3f%%", rep.truth_eta[i].std) + " |\n");
    for (const auto* w : host::AnalysedFlexions(rep.trials[i].windows, 5)) {
      csv.AddRow({std::to_string(i + 1), std::to_string(w->repetition),
                  CsvTable::Number(w->eta), CsvTable::Number(w->truth_eta),
                  CsvTable::Number(w->load), CsvTable::Number(w->truth_load),
                  CsvTable::Number(w->unload), CsvTable::Number(w->truth_unload)});
    }
    trials.push_back(
        {{"eta", StatsJson(rep.eta[i])}, {"truth_eta", StatsJson(rep.truth_eta[i])}});
  }
  Print("| Overall | " + Format("%.2f%%", rep.overall.mean) + " | " +
        Format("%.3f%%", rep.overall.std) + " | " +
        Format("%.2f%%", rep.truth_overall.mean) + " | " +
        Format("%.3f%%", rep.truth_overall.std) + " |\n");
  csv.Write(out_ / "repeatability.csv");
  json_["repeatability"] = {{"amplitude_deg", amplitude_deg},
                            {"trials", trials},
                            {"overall", StatsJson(rep.overall)},
                            {"truth_overall", StatsJson(rep.truth_overall)}};

  // Fig. 9: per trial, the mean of its three flexion power profiles ± one std.
  CsvTable prof({"fraction", "trial", "mean_mW", "std_mW", "truth_mean_mW"});
  double peak_fraction = 0.5;
  for (std::size_t i = 0; i < rep.trials.size(); ++i) {
    const auto flex = host::AnalysedFlexions(rep.trials[i].windows, 5);
    if (flex.empty()) continue;
    peak_fraction = flex.front()->peak_fraction;
    for (int k = 0; k < sim::kProfilePoints; ++k) {
      std::vector<double> v, tv;
      for (const auto* w : flex) {
        v.push_back(w->profile[static_cast<std::size_t>(k)] * kMilli);
        tv.push_back(w->truth_profile[static_cast<std::size_t>(k)] * kMilli);
      }
      const host::Stats s = host::Describe(v);
      prof.AddRow({CsvTable::Number(k / double{sim::kProfilePoints - 1}),
                   std::to_string(i + 1), CsvTable::Number(s.mean),
                   CsvTable::Number(s.std), CsvTable::Number(host::Describe(tv).mean)});
    }
  }
  prof.Write(out_ / "repeatability_profiles.csv");
  Figure("fig9_repeatability",
         "set title 'Interface power over the flexion window, five re-donned trials'\n"
         "set xlabel 'flexion window (fraction)'\nset ylabel 'power (mW)'\n"
         "set datafile separator ','\nset style fill transparent solid 0.2 noborder\n"
         "set arrow from " +
             Format("%.4f", peak_fraction) + ", graph 0 to " +
             Format("%.4f", peak_fraction) +
             ", graph 1 nohead dt 3\n"
             "plot for [t=1:5] 'repeatability_profiles.csv' every ::1 using "
             "1:($2==t ? $3-$4 : 1/0):($2==t ? $3+$4 : 1/0) with filledcurves notitle, "
             "for [t=1:5] '' every ::1 using 1:($2==t ? $3 : 1/0) with lines lw 2 title "
             "sprintf('trial %d', t)\n");
}

void Report::Amplitude(const std::vector<sim::SubjectSweep>& sweeps) {
  Print(
      "\n## Amplitude sweep (Figs. 10–12): work per flexion (mJ), mean ± SE of the "
      "middle "
      "three of five; board estimate vs plant truth\n");
  if (frequency_hz_ != sim::kPaperFrequencyHz) {
    Print("\ndrive frequency " + Format("%g", frequency_hz_) + " Hz (the paper's is " +
          Format("%g", sim::kPaperFrequencyHz) + " Hz)\n");
  }
  CsvTable csv({"subject", "amplitude_deg", "load_mJ", "load_se_mJ", "truth_load_mJ",
                "unload_mJ", "unload_se_mJ", "truth_unload_mJ", "net_mJ", "net_se_mJ",
                "truth_net_mJ", "eta_pct", "truth_eta_pct", "power_rmse_pct_peak"});
  nlohmann::json subjects = nlohmann::json::array();
  for (const auto& s : sweeps) {
    Print("\n### " + s.subject +
          "\n\n| amplitude | loading board | loading truth | unloading board | unloading "
          "truth | net board | net truth | η board | η truth |\n"
          "|---|---|---|---|---|---|---|---|---|\n");
    nlohmann::json points = nlohmann::json::array();
    for (const auto& p : s.points) {
      const WorkPoint work{.amplitude_deg = p.amplitude_deg,
                           .load = p.load,
                           .unload = p.unload,
                           .net = p.net,
                           .reference_load = p.truth_load.mean,
                           .reference_unload = p.truth_unload.mean,
                           .reference_net = p.truth_net.mean};
      Print(WorkCells(work) + " | " +
            EtaCell(p.eta, p.load.mean, s.noise_floor_J, "%.1f%%") + " | " +
            EtaCell(p.truth_eta, p.truth_load.mean, s.noise_floor_J, "%.1f%%") + " |\n");
      std::vector<std::string> row = WorkCsvCells(s.subject, work);
      row.insert(row.end(),
                 {CsvTable::Number(p.eta.mean), CsvTable::Number(p.truth_eta.mean),
                  CsvTable::Number(p.power_rmse_pct_peak)});
      csv.AddRow(row);
      nlohmann::json point = WorkJson(work);
      point["eta_pct"] = StatsJson(p.eta);
      point["truth_load_J"] = StatsJson(p.truth_load);
      point["truth_unload_J"] = StatsJson(p.truth_unload);
      point["truth_net_J"] = StatsJson(p.truth_net);
      point["truth_eta_pct"] = StatsJson(p.truth_eta);
      point["power_rmse_pct_peak"] = p.power_rmse_pct_peak;
      points.push_back(std::move(point));
    }
    nlohmann::json subject = {{"subject", s.subject}, {"points", points}};
    AddErrorsJson(ErrorsOf(s), &subject);
    subjects.push_back(std::move(subject));
  }
  csv.Write(out_ / "amplitude_sweep.csv");

  std::vector<SweepErrors> errors;
  for (const auto& s : sweeps) errors.push_back(ErrorsOf(s));
  Print("\n## Tables II–III: board estimate vs plant truth across amplitudes\n\n" +
        ErrorTable(errors, out_ / "rmse.csv"));
  json_["amplitude_sweep"] = subjects;

  // The attachment identified on the board, per subject and amplitude, beside the
  // plant's values (for a standard linear solid, its effective k and b at the drive
  // frequency).
  Print(
      "\n## The attachment identified on the board: τ = k_i·θ_j + b_i·θ̇_j + τ_0, mean ± "
      "SE of the analysed flexions\n\n| subject | amplitude | k_i board (N·m/rad) | k "
      "truth | k error | b_i board (N·m·s/rad) | b truth | b error |\n"
      "|---|---|---|---|---|---|---|---|\n");
  CsvTable fit({"subject", "amplitude_deg", "stiffness_Nm_rad", "stiffness_se",
                "truth_stiffness_Nm_rad", "damping_Nms_rad", "damping_se",
                "truth_damping_Nms_rad", "fits"});
  nlohmann::json fits = nlohmann::json::array();
  for (const auto& s : sweeps) {
    for (const auto& p : s.points) {
      const auto error = [](double board, double truth) {
        return truth != 0 ? Format("%+.1f%%", 100.0 * (board - truth) / truth)
                          : Format("%+.4f", board);
      };
      if (p.stiffness.n == 0) {
        Print("| " + s.subject + " | " + Format("%.0f°", p.amplitude_deg) +
              " | no fit | " + Format("%.3f", s.truth.stiffness) + " | | no fit | " +
              Format("%.4f", s.truth.damping) + " | |\n");
      } else {
        Print("| " + s.subject + " | " + Format("%.0f°", p.amplitude_deg) + " | " +
              PlusMinus(p.stiffness, 1.0, "%.3f", true) + " | " +
              Format("%.3f", s.truth.stiffness) + " | " +
              error(p.stiffness.mean, s.truth.stiffness) + " | " +
              PlusMinus(p.damping, 1.0, "%.4f", true) + " | " +
              Format("%.4f", s.truth.damping) + " | " +
              error(p.damping.mean, s.truth.damping) + " |\n");
      }
      fit.AddRow({s.subject, CsvTable::Number(p.amplitude_deg),
                  CsvTable::Number(p.stiffness.mean), CsvTable::Number(p.stiffness.se),
                  CsvTable::Number(s.truth.stiffness), CsvTable::Number(p.damping.mean),
                  CsvTable::Number(p.damping.se), CsvTable::Number(s.truth.damping),
                  std::to_string(p.stiffness.n)});
      fits.push_back({{"subject", s.subject},
                      {"amplitude_deg", p.amplitude_deg},
                      {"stiffness_Nm_rad", StatsJson(p.stiffness)},
                      {"damping_Nms_rad", StatsJson(p.damping)},
                      {"truth_stiffness_Nm_rad", s.truth.stiffness},
                      {"truth_damping_Nms_rad", s.truth.damping}});
    }
  }
  fit.Write(out_ / "attachment_fit.csv");
  json_["attachment_fit"] = fits;

  // Fidelity over the whole sweep.
  // η only where it can be judged (EtaCell): a window with loading work within the
  // noise floor has none worth comparing, and is counted instead.
  double worst_power = 0, worst_energy = 0, worst_eta = 0;
  int eta_unjudged = 0;
  for (const auto& s : sweeps) {
    for (const auto& p : s.points) {
      worst_power = std::max(worst_power, p.power_rmse_pct_peak);
      for (const auto& w : p.flexions) {
        worst_energy = std::max(worst_energy, WindowEnergyErrorPct(w));
        if (std::isfinite(w.eta) && std::isfinite(w.truth_eta) &&
            w.truth_load > s.noise_floor_J) {
          worst_eta = std::max(worst_eta, std::fabs(w.eta - w.truth_eta));
        } else {
          ++eta_unjudged;
        }
      }
    }
  }
  Print("\nfidelity over the sweep: power RMSE ≤ " + Format("%.2f", worst_power) +
        "% of peak, window energy within " + Format("%.2f", worst_energy) +
        "%, η within " + Format("%.2f", worst_eta) + " points" +
        (eta_unjudged > 0 ? " (" + std::to_string(eta_unjudged) +
                                " windows with loading work too small to judge η)"
                          : std::string()) +
        "\n");
  if (worst_energy > kWindowEnergyBoundPct) {
    Warn("window energies up to " + Format("%.1f", worst_energy) +
         " % off the plant's truth, beyond the " + Format("%.0f", kWindowEnergyBoundPct) +
         " % the default joint is held to: " +
         (described_ ? "is the robot description the plant's joint?"
                     : "no robot description, the board assumed the default joint "
                       "(--robot-description)"));
  }
  json_["fidelity"] = {{"power_rmse_pct_peak", worst_power},
                       {"window_energy_err_pct", worst_energy},
                       {"eta_err_pt", worst_eta},
                       {"eta_windows_unjudged", eta_unjudged}};

  work_subjects_.clear();
  for (const auto& sw : sweeps) work_subjects_.push_back(sw.subject);
  work_figures_pending_ = true;
}

// Figs. 10–12: the board's work per flexion against amplitude with its SE, the plant's
// truth, and, once Model has run, the model's prediction as the paper's dotted lines.
void Report::WorkFigures(bool with_model) {
  work_figures_pending_ = false;
  // Columns of amplitude_sweep.csv (mean, SE, truth) and of model_vs_board.csv (the
  // prediction).
  const char* quantities[3][4] = {{"fig10_loading", "Loading work", "3:4:5", "5"},
                                  {"fig11_unloading", "Unloading work", "6:7:8", "8"},
                                  {"fig12_net", "Net work", "9:10:11", "11"}};
  for (const auto& q : quantities) {
    const std::string cols = q[2];
    const std::string mean = cols.substr(0, cols.find(':'));
    const std::string rest = cols.substr(cols.find(':') + 1);
    const std::string se = rest.substr(0, rest.find(':'));
    const std::string truth = rest.substr(rest.find(':') + 1);
    std::string plot = "plot ";
    for (std::size_t i = 0; i < work_subjects_.size(); ++i) {
      const std::string& subject = work_subjects_[i];
      const std::string sel = "(strcol(1) eq '" + subject + "' ? $";
      const std::string colour = std::to_string(i + 1);
      plot += std::string(i ? ", " : "") +
              "'amplitude_sweep.csv' every ::1 using 2:" + sel + mean + " : 1/0):" + sel +
              se + " : 1/0) with yerrorlines lw 2 lc " + colour + " title '" + subject +
              " board', '' every ::1 using 2:" + sel + truth +
              " : 1/0) with points pt 6 ps 1.5 lc " + colour + " title '" + subject +
              " truth'";
      if (with_model) {
        plot += ", 'model_vs_board.csv' every ::1 using 2:" + sel + q[3] +
                " : 1/0) with lines dt 2 lw 2 lc " + colour + " title '" + subject +
                " model'";
      }
    }
    Figure(q[0], std::string("set title '") + q[1] +
                     " per flexion vs amplitude'\nset xlabel 'amplitude (deg)'\n"
                     "set ylabel 'work (mJ)'\nset datafile separator ','\n" +
                     plot + "\n");
  }
}

void Report::Model(const std::vector<sim::ModelComparison>& comparisons) {
  Print(
      "\n## Experiment against model (Figs. 10–12, Tables II–III): the board's "
      "measurement vs the simulator's prediction with the attachment the board "
      "identified (Kelvin–Voigt, mean of its fits at ≥ 11°); work per flexion (mJ)\n");
  CsvTable csv({"subject", "amplitude_deg", "load_mJ", "load_se_mJ", "model_load_mJ",
                "unload_mJ", "unload_se_mJ", "model_unload_mJ", "net_mJ", "net_se_mJ",
                "model_net_mJ"});
  nlohmann::json subjects = nlohmann::json::array();
  for (const auto& c : comparisons) {
    Print("\n### " + c.subject +
          ": model k = " + Format("%.3f", c.model.stiffness_Nm_per_rad) +
          " N·m/rad, b = " + Format("%.4f", c.model.damping_Nm_s_per_rad) +
          " N·m·s/rad, τ_0 = " + Format("%+.4f", c.model.preload_Nm) + " N·m (" +
          std::to_string(c.identified.stiffness.n) +
          " fits)\n\n| amplitude | loading board | loading model | unloading board | "
          "unloading model | net board | net model |\n|---|---|---|---|---|---|---|\n");
    nlohmann::json points = nlohmann::json::array();
    for (const auto& p : c.points) {
      const WorkPoint work{.amplitude_deg = p.amplitude_deg,
                           .load = p.load,
                           .unload = p.unload,
                           .net = p.net,
                           .reference_load = p.model_load,
                           .reference_unload = p.model_unload,
                           .reference_net = p.model_net};
      Print(WorkCells(work) + " |\n");
      csv.AddRow(WorkCsvCells(c.subject, work));
      nlohmann::json point = WorkJson(work);
      point["model_load_J"] = p.model_load;
      point["model_unload_J"] = p.model_unload;
      point["model_net_J"] = p.model_net;
      points.push_back(std::move(point));
    }
    subjects.push_back({{"subject", c.subject},
                        {"model",
                         {{"stiffness_Nm_rad", c.model.stiffness_Nm_per_rad},
                          {"damping_Nms_rad", c.model.damping_Nm_s_per_rad},
                          {"preload_Nm", c.model.preload_Nm}}},
                        {"identified",
                         {{"stiffness_Nm_rad", StatsJson(c.identified.stiffness)},
                          {"damping_Nms_rad", StatsJson(c.identified.damping)},
                          {"offset_Nm", StatsJson(c.identified.offset)}}},
                        {"points", points}});
    AddErrorsJson(ErrorsOf(c), &subjects.back());
  }
  csv.Write(out_ / "model_vs_board.csv");

  std::vector<SweepErrors> errors;
  for (const auto& c : comparisons) errors.push_back(ErrorsOf(c));
  Print(
      "\n## Tables II–III: experiment (board) vs simulation (model) across amplitudes; "
      "NRMSE normalised to the prediction's range\n\n" +
      ErrorTable(errors, out_ / "model_rmse.csv"));
  json_["model_vs_board"] = subjects;
  WorkFigures(true);
}

int Report::Finish(double wall_s, double simulated_s) {
  if (work_figures_pending_) WorkFigures(false);
  json_["run"] = {{"frequency_hz", frequency_hz_},
                  {"wall_s", wall_s},
                  {"simulated_s", simulated_s},
                  {"realtime_factor", wall_s > 0 ? simulated_s / wall_s : 0.0},
                  {"figures", figures_}};
  // Where the numbers come from (sim/scenarios.h): what a lab's tools would get, and
  // what only the simulator can read on the board's side of the bus.
  json_["run"]["sources"] = {
      {"protocol",
       "calibration: the sweep's angle telemetry, the fit, the record uploaded over "
       "ISO-TP and read back; trials: every window's energies, eta, ticks and "
       "attachment fit as the board's window frames carried them"},
      {"board_side_probe",
       "the plant's truth (interface energy and power per tick, aligned to the "
       "windows' ticks); the board's power every tick (power RMSE, Fig. 9 profiles); "
       "Fig. 8's trace"}};
  std::ofstream(out_ / "results.json") << json_.dump(2) << '\n';
  std::ofstream(out_ / "tables.md")
      << "# Interface power on the simulated Maestro joint\n"
      << tables_;
  Print("\nsimulated " + Format("%.1f", simulated_s) + " s in " + Format("%.1f", wall_s) +
        " s wall (" + Format("%.0f", wall_s > 0 ? simulated_s / wall_s : 0.0) +
        "× real time)\noutputs in " + out_.string() +
        ": tables.md, results.json, *.csv, " + std::to_string(figures_.size()) +
        " figures (*.png)\n");
  return failed_figures_;
}

int Run(const std::string& scenario, const plant::PlantParams& robot,
        const std::vector<plant::PlantParams>& subjects, const ControlConfig& config,
        std::uint64_t seed, int threads, double frequency_hz, Report& report,
        const Joint& joint) {
  const auto start = std::chrono::steady_clock::now();
  // The board on a bus of its own, calibrated by the host library as `mjc calibrate`
  // calibrates one; the trials then run over buses of their own as `mjc trial` runs
  // them (sim/scenarios.h says which figures come over the bus and which from the
  // board's side).
  sim::BusBoard board(robot, config);
  if (board.app().control().config().velocity_window != config.velocity_window) {
    throw std::runtime_error("the board refused the configuration (velocity window " +
                             std::to_string(config.velocity_window) + ")");
  }
  report.Robot(joint, robot);
  // The joint's limits before anything moves, as `mjc calibrate --robot` sends them.
  if (joint.robot) {
    const host::ParamWriteOutcome limits =
        host::SendJointLimits(board.client(), *joint.robot, 500);
    if (limits.end != host::ParamWriteEnd::kDone) {
      throw std::runtime_error("sending " + joint.robot->name +
                               "'s limits: " + limits.why);
    }
  }
  // The calibration the board holds before the sweep, for the refit below: read on
  // the board's side, so that the sweep starts on the same tick with or without the
  // refit (the host's ReadCalibration would hold the bus for a few ticks).
  const ControlConfig& before = board.app().control().config();
  protocol::CalibrationRecord held;
  held.backlash = before.backlash;
  held.sea_stiffness = before.sea_stiffness;
  held.joint_zero_count = before.joint_encoder.zero_offset;
  report.Progress("calibration sweep on the robot alone", 0.0);
  const sim::CalibrationOutcome cal =
      sim::RunCalibration(board, sim::PaperCalibrationSweep(), {joint.robot, false});
  report.Calibration(cal);
  // The sweep refitted with α free, whether or not its fit was refused. Without a
  // description the board assumed the default joint: checked against it.
  std::string why;
  const auto rate_hz =
      board.client().ReadParam(protocol::ParamId::kTelemetryAnglesHz, 500, &why);
  if (!rate_hz) throw std::runtime_error("the board did not answer: " + why);
  if (!cal.motor_rad.empty()) {
    const host::RobotDescription assumed;
    const host::RobotDescription& described = joint.robot ? *joint.robot : assumed;
    const host::SweepCalibration free =
        host::FitSweep(cal.motor_rad, cal.joint_rad, static_cast<double>(*rate_hz), held,
                       &described, true);
    report.Check({.described_alpha = described.Alpha(),
                  .fixed_rms_rad = cal.fit.rms_error_rad,
                  .free_fitted = free.record.has_value(),
                  .free_alpha = free.fit.alpha,
                  .free_rms_rad = free.fit.rms_error_rad,
                  .free_message = free.record ? "" : free.why});
  }
  if (!cal.uploaded) {
    std::fprintf(stderr, "mjc-paper: calibration failed: %s\n", cal.message.c_str());
    // What the sweep showed stays in tables.md and results.json.
    (void)report.Finish(
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(),
        board.plant().time());
    return 2;
  }
  const bool all = scenario == "all";
  const bool repeatability = all || scenario == "repeatability";
  const bool amplitude_sweep = all || scenario == "amplitude";
  const double amplitude = 25.0;
  const std::vector<double>& amplitudes = kAmplitudesDeg;
  if (subjects.empty() && scenario != "calibration") {
    throw std::runtime_error("no subject parameter sets given");
  }

  // Every trial on a board of its own, calibrated with the record the sweep uploaded
  // (as a board powered up with its stored calibration), so they can run on any
  // thread: Fig. 8's trial, the five re-donned trials, then subject by subject the
  // amplitudes.
  std::vector<sim::TrialSpec> specs;
  if (repeatability) {
    const plant::PlantParams& first = subjects.front();
    specs.push_back(
        {first.interface, amplitude, true, 0, "one trial: " + first.name, frequency_hz});
    for (std::uint64_t k = 0; k < 5; ++k) {
      specs.push_back({plant::Redon(first, seed + k).interface, amplitude, false, 0,
                       "repeatability: trial " + std::to_string(k + 1) + "/5",
                       frequency_hz});
    }
  }
  const std::size_t sweep_from = specs.size();
  if (amplitude_sweep) {
    for (const plant::PlantParams& subject : subjects) {
      for (const double a : amplitudes) {
        specs.push_back({subject.interface, a, false, 0,
                         "amplitude sweep: " + subject.name + " " +
                             std::to_string(static_cast<int>(a)) + "°",
                         frequency_hz});
      }
    }
  }
  for (std::size_t i = 0; i < specs.size(); ++i) specs[i].noise_seed = RunSeed(seed, i);
  // The model's sweep follows the measured one (it needs its fits): a quarter of the
  // progress bar.
  const double measured_to = amplitude_sweep ? 0.75 : 1.0;
  const std::vector<sim::TrialOutcome> trials = sim::RunTrials(
      robot, config, cal.record, specs, threads,
      [&report, measured_to](const std::string& s, double f) {
        report.Progress(s, 0.1 + (measured_to - 0.1) * f);
      },
      joint.robot);

  // Reported in the order of the list, whatever the order the trials ended in.
  double simulated_s = board.plant().time();
  for (const sim::TrialOutcome& t : trials) {
    simulated_s += (t.ticks + 1.0) / board.tick_hz();  // the calibration's tick too
  }
  if (repeatability) {
    report.Trial(trials[0], amplitude);
    report.Repeatability(
        sim::SummariseRepeatability({trials.begin() + 1, trials.begin() + 6}), amplitude);
  }
  if (amplitude_sweep) {
    std::vector<sim::SubjectSweep> sweeps;
    std::size_t next = sweep_from;
    for (const plant::PlantParams& subject : subjects) {
      std::vector<sim::AmplitudePoint> points;
      for (const double a : amplitudes)
        points.push_back(sim::SummarisePoint(a, trials[next++]));
      sweeps.push_back(sim::SummariseSweep(subject.name, std::move(points)));
      sweeps.back().truth = sim::TrueInterface(subject.interface, frequency_hz);
      sweeps.back().frequency_hz = frequency_hz;
    }
    report.Amplitude(sweeps);

    // The prediction: the same sweep on each subject's identified attachment, every
    // trial on a board of its own with a noise sequence of its own.
    std::vector<sim::IdentifiedAttachment> identified;
    std::vector<sim::TrialSpec> model_specs;
    for (const sim::SubjectSweep& s : sweeps) {
      identified.push_back(sim::IdentifyAttachment(s));
      const plant::InterfaceParams model = sim::ModelInterface(identified.back(), robot);
      for (const double a : amplitudes) {
        model_specs.push_back(
            {model, a, false, RunSeed(seed, specs.size() + model_specs.size()),
             "model: " + s.subject + " " + std::to_string(static_cast<int>(a)) + "°",
             frequency_hz});
      }
    }
    const std::vector<sim::TrialOutcome> predicted = sim::RunTrials(
        robot, config, cal.record, model_specs, threads,
        [&report, measured_to](const std::string& s, double f) {
          report.Progress(s, measured_to + (1.0 - measured_to) * f);
        },
        joint.robot);
    std::vector<sim::ModelComparison> comparisons;
    next = 0;
    for (std::size_t i = 0; i < sweeps.size(); ++i) {
      std::vector<sim::AmplitudePoint> points;
      for (const double a : amplitudes)
        points.push_back(sim::SummarisePoint(a, predicted[next++]));
      comparisons.push_back(sim::CompareWithModel(
          sweeps[i], sim::SummariseSweep(sweeps[i].subject, std::move(points)),
          identified[i], model_specs[i * amplitudes.size()].interface));
    }
    for (const sim::TrialOutcome& t : predicted) {
      simulated_s += (t.ticks + 1.0) / board.tick_hz();
    }
    report.Model(comparisons);
  }
  report.Progress("done", 1.0);
  const double wall =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return report.Finish(wall, simulated_s) == 0 ? 0 : 3;
}

}  // namespace mjc::paper
