#include "experiment_rig.h"

#include <numbers>
#include <random>
#include <stdexcept>

#include "mjc/app/joint_config.h"
#include "mjc/sim/robot_plant.h"

namespace mjc::sim::rig {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

// Runs one spec per subject and amplitude on `interfaces[subject]` and summarises
// them as sweeps, in the subjects' order.
std::vector<SubjectSweep> RunSweeps(const plant::PlantParams& robot,
                                    const Calibration& record,
                                    const std::vector<std::string>& names,
                                    const std::vector<plant::InterfaceParams>& interfaces,
                                    const std::vector<double>& amplitudes_deg,
                                    double frequency_hz, std::mt19937_64& seeds,
                                    int threads) {
  std::vector<TrialSpec> specs;
  for (std::size_t s = 0; s < names.size(); ++s) {
    for (const double a : amplitudes_deg) {
      specs.push_back({interfaces[s], a, false, seeds(), names[s], frequency_hz});
    }
  }
  const std::vector<TrialOutcome> trials =
      RunTrials(robot, app::DefaultJointConfig(), record, specs, threads, nullptr);
  std::vector<SubjectSweep> sweeps;
  std::size_t next = 0;
  for (std::size_t s = 0; s < names.size(); ++s) {
    std::vector<AmplitudePoint> points;
    for (const double a : amplitudes_deg) {
      if (trials[next].faulted) {
        throw std::runtime_error(names[s] + ": " + trials[next].fault);
      }
      points.push_back(SummarisePoint(a, trials[next++]));
    }
    sweeps.push_back(SummariseSweep(names[s], std::move(points)));
    sweeps.back().truth = TrueInterface(interfaces[s], frequency_hz);
    sweeps.back().frequency_hz = frequency_hz;
  }
  return sweeps;
}

}  // namespace

plant::PlantParams PaperRobot() {
  plant::PlantParams p = plant::LoadPlantParams("default");
  p.integration.max_step_s = 100e-6;
  return p;
}

ModelRun RunModelAgainstBoard(const plant::PlantParams& robot, const Calibration& record,
                              const std::vector<plant::PlantParams>& subjects,
                              const std::vector<double>& amplitudes_deg,
                              double frequency_hz, std::uint64_t seed, int threads) {
  std::mt19937_64 seeds(seed);
  std::vector<std::string> names;
  std::vector<plant::InterfaceParams> interfaces;
  for (const plant::PlantParams& s : subjects) {
    names.push_back(s.name);
    interfaces.push_back(s.interface);
  }
  ModelRun out;
  out.measured = RunSweeps(robot, record, names, interfaces, amplitudes_deg, frequency_hz,
                           seeds, threads);
  std::vector<IdentifiedAttachment> identified;
  std::vector<plant::InterfaceParams> models;
  for (const SubjectSweep& s : out.measured) {
    identified.push_back(IdentifyAttachment(s));
    models.push_back(ModelInterface(identified.back(), robot));
  }
  out.predicted = RunSweeps(robot, record, names, models, amplitudes_deg, frequency_hz,
                            seeds, threads);
  for (std::size_t s = 0; s < subjects.size(); ++s) {
    out.comparisons.push_back(
        CompareWithModel(out.measured[s], out.predicted[s], identified[s], models[s]));
  }
  return out;
}

plant::PlantParams RobotWithJointHeld(double stiffness_Nm_per_rad) {
  plant::PlantParams p = PaperRobot();
  p.name = "default, joint held";
  p.interface.present = true;
  p.interface.model = plant::InterfaceModel::kKelvinVoigt;
  p.interface.stiffness_Nm_per_rad = stiffness_Nm_per_rad;
  p.interface.damping_Nm_s_per_rad = 0.0;
  p.interface.preload_Nm = 0.0;
  // The joint on the jammed attachment rings at ~8,200 rad/s: the plant asks for
  // substeps of at most 24 µs to follow it (five a tick).
  p.integration.max_step_s = 20e-6;
  plant::ValidatePlantParams(p, p.name);
  return p;
}

CalibrationOutcome CalibrateHeldJoint(double stiffness_Nm_per_rad) {
  SimBoard board(RobotWithJointHeld(stiffness_Nm_per_rad), app::DefaultJointConfig());
  return RunCalibration(board, PaperCalibrationSweep());
}

host::RobotDescription AlphaExampleRobot(const std::string& robots_dir) {
  std::string why;
  const auto robot =
      host::LoadRobotDescription(robots_dir + "/example-alpha-1.25.json", &why);
  if (!robot) throw std::runtime_error(why);
  return *robot;
}

plant::PlantParams AlphaExamplePlant(const host::RobotDescription& robot) {
  plant::PlantParams base = plant::LoadPlantParams("default");
  base.cable.c_right_rad = 1.6 * kDeg;
  base.cable.c_left_rad = -0.7 * kDeg;
  return PlantForRobot(robot, base, app::DefaultJointConfig(), "example-alpha-1.25.json");
}

}  // namespace mjc::sim::rig
