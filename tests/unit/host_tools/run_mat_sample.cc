// Writes two run folders as the tools write them, for check_run_mat.py to read back
// with scipy: DIR/trial (windows.csv through WindowsCsvWriter, run.json through
// WriteRunRecord, which writes run.mat once the run has ended) and DIR/calibrate (a
// sweep.csv of angle samples and a calibration.json). The windows are drawn from a
// seeded generator over the ranges the board sends, so no value is chosen to suit the
// writer. Usage: run_mat_sample DIR
#include <cstdio>
#include <filesystem>
#include <random>
#include <string>

#include "mjc/host/report.h"
#include "mjc/host/run_record.h"
#include "mjc/host/trial_report.h"

namespace {

using namespace mjc;
using namespace mjc::host;

BoardWindow RandomWindow(std::mt19937& rng, std::uint16_t repetition, bool flexion) {
  std::uniform_real_distribution<double> energy(0.0001, 0.05), work(0.0, 0.08),
      eta(0.0, 99.0), torque(-2.0, 2.0), k(2.0, 12.0), b(0.0, 0.6);
  BoardWindow w;
  w.motion = flexion ? Motion::kFlexion : Motion::kExtension;
  w.repetition = repetition;
  w.loading_J = energy(rng);
  w.unloading_J = -energy(rng) * 0.5;
  w.positive_J = work(rng);
  w.negative_J = -work(rng);
  w.eta_valid = rng() % 5 != 0;
  w.eta_percent = eta(rng);
  w.peak_power_W = energy(rng) * 10;
  w.peak_torque_Nm = torque(rng);
  w.fit_valid = rng() % 4 != 0;
  w.stiffness_Nm_rad = k(rng);
  w.damping_Nms_rad = b(rng);
  w.offset_Nm = torque(rng) * 0.01;
  w.residual_rms_Nm = energy(rng);
  return w;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: run_mat_sample DIR\n");
    return 2;
  }
  const std::filesystem::path root = argv[1];
  std::filesystem::remove_all(root / "trial");
  std::filesystem::remove_all(root / "calibrate");
  std::mt19937 rng(20261128);
  try {
    const std::filesystem::path trial = root / "trial";
    std::filesystem::create_directories(trial);
    RunRecord record;
    record.command = "trial";
    record.node = 3;
    record.iface = "vcan0";
    record.protocol = "amplitude";
    record.amplitudes_deg = {6, 11, 25};
    record.frequency_hz = 0.5;
    record.repetitions = 5;
    WriteRunRecord(record, trial);  // running: no run.mat yet
    if (std::filesystem::exists(trial / "run.mat")) {
      std::fprintf(stderr, "run_mat_sample: run.mat written while the run goes on\n");
      return 1;
    }
    WindowsCsvWriter csv(trial);
    for (std::size_t t = 0; t < record.amplitudes_deg.size(); ++t) {
      for (std::uint16_t r = 0; r < 5; ++r) {
        for (const bool flexion : {true, false}) {
          csv.Append(t, record.amplitudes_deg[t], 5, RandomWindow(rng, r, flexion));
        }
      }
    }
    record.end.outcome = "completed";
    WriteRunRecord(record, trial);

    const std::filesystem::path cal = root / "calibrate";
    std::filesystem::create_directories(cal);
    std::string sweep =
        "# mjc calibrate sweep: the board's angle telemetry at 1000 Hz\n"
        "motor_rad,joint_rad\n";
    std::normal_distribution<double> angle(0.0, 0.3);
    char line[64];
    for (int i = 0; i < 2000; ++i) {
      std::snprintf(line, sizeof line, "%.9g,%.9g\n", angle(rng), angle(rng));
      sweep += line;
    }
    ReplaceFile(cal / "sweep.csv", sweep);
    ReplaceFile(cal / "calibration.json",
                "{\"c_right_deg\": 1.1, \"c_left_deg\": -0.9, \"alpha\": 1.0}\n");
    RunRecord cal_record;
    cal_record.command = "calibrate";
    cal_record.protocol = "sweep";
    cal_record.end.outcome = "completed";
    WriteRunRecord(cal_record, cal);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "run_mat_sample: %s\n", e.what());
    return 1;
  }
  return 0;
}
