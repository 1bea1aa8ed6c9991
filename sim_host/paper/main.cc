// mjc-paper: reproduces the interface-power paper's experiments on the simulated joint
// board (the unmodified firmware against the physical plant): calibration (Fig. 7),
// one trial's time series (Fig. 8), repeatability (Table I, Fig. 9) and the amplitude
// sweep (Figs. 10–12, Tables II–III), board estimate against plant ground truth.
// Prints the tables, writes CSV and JSON of every number and PNG figures (gnuplot).
#include <CLI/CLI.hpp>
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

#include "mjc/host/report.h"
#include "mjc/host/robot_description.h"
#include "mjc/host/run_record.h"
#include "mjc/plant/params.h"
#include "mjc/sim/robot_plant.h"
#include "mjc/sim/scenarios.h"
#include "paper_report.h"
#include "sweep.h"

namespace {

using namespace mjc;

struct Options {
  std::string scenario = "all";
  std::string robot = "default";
  std::string robot_description;  // a robots/*.json file; empty: the default joint
  std::vector<std::string> subjects = {"subject1", "subject2", "subject3"};
  std::string out = "out/paper";
  bool noise = true;
  std::uint64_t seed = 1;
  bool quiet = false;
  int velocity_window = 0;  // 0: the board's default
  // One implicit substep a 10 kHz tick, as in the parameter files: the tables agree
  // with 10 µs substeps within 0.2 % (tests/sim, step independence). The plant refuses
  // a step too long for a mode the sensors follow.
  double max_step_us = 100.0;
  int threads = 0;  // 0: one per core
  double frequency_hz = sim::kPaperFrequencyHz;
  // --scenario sweep (sweep.h).
  std::string grid;
  std::string shard;
  std::vector<std::string> merge;
};

plant::PlantParams Load(const std::string& name_or_path) {
  if (name_or_path.find('/') != std::string::npos || name_or_path.ends_with(".json")) {
    return plant::LoadPlantParamsFile(name_or_path);
  }
  return plant::LoadPlantParams(name_or_path);
}

}  // namespace

int main(int argc, char** argv) {
  Options opt;
  CLI::App cli{
      "Reproduces the interface-power paper's experiments on the simulated joint board:\n"
      "calibration sweep and fit, repeatability (Table I, Fig. 9), amplitude sweep\n"
      "(Figs. 10-12, Tables II-III). Board estimates are compared with plant ground "
      "truth."};
  cli.add_option("--scenario", opt.scenario, "Which experiment to run")
      ->check(
          CLI::IsMember({"all", "calibration", "repeatability", "amplitude", "sweep"}))
      ->capture_default_str();
  auto* robot_option =
      cli.add_option("--robot", opt.robot,
                     "Plant parameter set for the robot alone (calibration): a name in "
                     "sim_host/params or a .json path; with --robot-description and "
                     "without --robot, the default set with the described joint")
          ->capture_default_str();
  cli.add_option("--robot-description", opt.robot_description,
                 "The joint's robot description (robots/*.json), as mjc calibrate "
                 "--robot takes it: the board's joint limits, the fit's alpha, the "
                 "record's stiffness, cable friction and joint zero come from it");
  cli.add_option(
         "--subjects", opt.subjects,
         "Plant parameter sets of the subjects (names or .json paths); the first is "
         "used for repeatability")
      ->capture_default_str();
  cli.add_option("--out", opt.out, "Output folder for tables, CSV, JSON and figures")
      ->capture_default_str();
  cli.add_option("--noise", opt.noise,
                 "Sensor noise from the parameter files (true/false)")
      ->capture_default_str();
  cli.add_option("--seed", opt.seed, "Seed of re-donning perturbations and sensor noise")
      ->capture_default_str();
  cli.add_flag("--quiet", opt.quiet, "No progress lines");
  cli.add_option("--velocity-window", opt.velocity_window,
                 "The board's velocity window in ticks (odd, 33..1001; 0: its default)")
      ->check(CLI::Range(0, 1001));
  cli.add_option("--max-step-us", opt.max_step_us,
                 "Longest substep of the plant, µs (the parameter files use 100)")
      ->check(CLI::Range(0.1, 1000.0))
      ->capture_default_str();
  cli.add_option(
         "--threads", opt.threads,
         "Threads for the trials (0: one per core, 1: serial); the results do not "
         "depend on it")
      ->check(CLI::Range(0, 1024))
      ->capture_default_str();
  cli.add_option("--frequency-hz", opt.frequency_hz,
                 "Drive frequency of the trials, Hz (0.25 to 2; the paper's is 0.5). The "
                 "calibration sweep keeps its own 0.5 Hz")
      ->capture_default_str();
  auto* grid_option = cli.add_option(
      "--grid", opt.grid,
      "With --scenario sweep: the grid file (JSON; sim_host/README.md, "
      "\"Design-space sweep\"); its robot, subject and frequencies replace "
      "--robot, --subjects and --frequency-hz");
  auto* shard_option = cli.add_option(
      "--shard", opt.shard,
      "With --scenario sweep: i/n runs only the grid's points whose index % n == i");
  auto* merge_option = cli.add_option(
      "--merge", opt.merge,
      "With --scenario sweep: joins these shards' --out folders into --out's summary");
  CLI11_PARSE(cli, argc, argv);
  if (opt.scenario == "sweep") {
    for (const auto* o :
         {robot_option, cli.get_option("--robot-description"),
          cli.get_option("--subjects"), cli.get_option("--frequency-hz")}) {
      if (o->count() != 0) {
        std::fprintf(stderr, "mjc-paper: %s is set in the sweep's grid file, not here\n",
                     o->get_name().c_str());
        return 2;
      }
    }
    if (cli.get_option("--out")->count() == 0) opt.out = "out/sweep";
    paper::SweepCommand sweep{.grid_path = opt.grid,
                              .merge = opt.merge,
                              .out = opt.out,
                              .shard = opt.shard,
                              .threads = opt.threads,
                              .quiet = opt.quiet,
                              .settings = {.noise = opt.noise,
                                           .max_step_us = opt.max_step_us,
                                           .velocity_window = opt.velocity_window}};
    return paper::SweepMain(sweep);
  }
  for (const auto* o : {grid_option, shard_option, merge_option}) {
    if (o->count() != 0) {
      std::fprintf(stderr, "mjc-paper: %s is for --scenario sweep\n",
                   o->get_name().c_str());
      return 2;
    }
  }
  // Checked here rather than by CLI11, for one line naming the range; NaN fails too.
  if (!(opt.frequency_hz >= sim::kMinDriveFrequencyHz &&
        opt.frequency_hz <= sim::kMaxDriveFrequencyHz)) {
    std::fprintf(
        stderr, "mjc-paper: --frequency-hz %g is outside the checked range %g to %g Hz\n",
        opt.frequency_hz, sim::kMinDriveFrequencyHz, sim::kMaxDriveFrequencyHz);
    return 2;
  }

  // The joint's description before anything runs or is written: a bad one is refused
  // in one line, as `mjc calibrate --robot` refuses it.
  paper::Joint joint;
  std::optional<host::RobotDescription> described;
  plant::PlantParams robot;
  try {
    robot = Load(opt.robot);
    if (!opt.robot_description.empty()) {
      std::string why;
      described = host::LoadRobotDescription(opt.robot_description, &why);
      if (!described) {
        std::fprintf(stderr, "mjc-paper: robot description refused: %s\n", why.c_str());
        return 1;
      }
      // Without --robot the plant is the described joint on the default set, as `mjc
      // sim --robot-description` builds it; with it, the set given is the truth and the
      // description what the board is told.
      if (robot_option->count() == 0) {
        robot = sim::PlantForRobot(*described, robot, app::DefaultJointConfig(),
                                   opt.robot_description);
      }
      // The paper's calibration sweep and its largest trial turn the motor pulley
      // ±30° and ±25°: the joint must have the travel for α times that.
      const std::string beyond = paper::TravelRefusal(*described);
      if (!beyond.empty()) {
        std::fprintf(stderr, "mjc-paper: %s\n", beyond.c_str());
        return 2;
      }
      joint.robot = &*described;
      joint.path = opt.robot_description;
      joint.record = host::RobotRecord(
          opt.robot_description, host::ReadFileText(opt.robot_description).value_or(""));
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "mjc-paper: %s\n", e.what());
    return 1;
  }

  paper::Report report(opt.out, opt.quiet, opt.frequency_hz);
  try {
    std::vector<plant::PlantParams> subjects;
    for (const auto& s : opt.subjects) subjects.push_back(Load(s));
    robot.sensors.noise_seed = opt.seed;
    robot.integration.max_step_s = opt.max_step_us * 1e-6;
    plant::ValidatePlantParams(robot, "--max-step-us");
    if (!opt.noise) {
      robot.sensors.joint_noise_counts = 0;
      robot.sensors.motor_noise_counts = 0;
    }
    ControlConfig config = app::DefaultJointConfig();
    if (opt.velocity_window != 0) {
      config.velocity_window = static_cast<std::uint16_t>(opt.velocity_window);
    }
    return paper::Run(opt.scenario, robot, subjects, config, opt.seed, opt.threads,
                      opt.frequency_hz, report, joint);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "mjc-paper: %s\n", e.what());
    return 1;
  }
}
