// Orchestration and output of mjc-paper: calibrates a simulated board, runs the
// scenarios' trials (on threads, each on a board of its own) and turns their outcomes
// into printed tables, CSV, JSON and gnuplot figures.
#pragma once

#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "mjc/host/robot_description.h"
#include "mjc/plant/params.h"
#include "mjc/sim/scenarios.h"

namespace mjc::paper {

// The joint the board is told it runs: a robot description (robots/*.json) as `mjc
// calibrate --robot` reads it, or none: the default joint assumed (α = 1, the board's
// own stiffness and joint zero), as `mjc calibrate` without --robot.
struct Joint {
  const host::RobotDescription* robot = nullptr;
  std::string path;
  nlohmann::json record;  // host::RobotRecord: the path and the description as read
};

// Why the paper's motions cannot run on the described joint, in one line (empty: they
// can): the calibration sweep turns the motor pulley ±30° and the largest trial ±25°,
// and the joint follows at α times that (host::TravelViolation against its travel).
std::string TravelRefusal(const host::RobotDescription& robot);

// What the calibration sweep alone says of the joint against its description: the
// same samples refitted with α free within ±20 % of the description's (host::FitSweep
// with fit_alpha, the record discarded). A plant whose transmission is not the
// described one shows as a fitted α away from it, or a fit ending on its bound, and
// as a residual well above the free fit's.
struct JointCheck {
  double described_alpha = 1;
  double fixed_rms_rad = 0;  // the calibration's fit, α fixed at the description's
  bool free_fitted = false;  // the free fit converged inside its bounds
  double free_alpha = 0;
  double free_rms_rad = 0;
  std::string free_message;
};

class Report {
 public:
  // `frequency_hz`: the trials' drive frequency, for titles and results.json.
  Report(std::filesystem::path out, bool quiet,
         double frequency_hz = sim::kPaperFrequencyHz);

  void Progress(const std::string& stage, double fraction);
  // The joint: its description (or none) against the plant, which only the simulator
  // knows (what a description that is not the plant's joint does to the numbers).
  void Robot(const Joint& joint, const plant::PlantParams& plant);
  void Calibration(const sim::CalibrationOutcome& cal);
  // What the board's calibration sweep tells of the description (JointCheck).
  void Check(const JointCheck& check);
  void Trial(const sim::TrialOutcome& trial, double amplitude_deg);
  void Repeatability(const sim::RepeatabilityOutcome& rep, double amplitude_deg);
  void Amplitude(const std::vector<sim::SubjectSweep>& sweeps);
  // The board's measurement against the simulator's prediction from the attachment it
  // identified (the paper's experiment against simulation, Tables II–III).
  void Model(const std::vector<sim::ModelComparison>& comparisons);
  // Writes results.json and tables.md; returns the number of figures that failed.
  int Finish(double wall_s, double simulated_s);

  const std::filesystem::path& out() const { return out_; }

 private:
  void Print(const std::string& text);
  // A line on stderr and in tables.md: a number that is not what it should be.
  void Warn(const std::string& text);
  void Figure(const std::string& name, const std::string& script);
  void WorkFigures(bool with_model);

  std::filesystem::path out_;
  bool quiet_;
  double frequency_hz_;
  std::string tables_;
  nlohmann::json json_;
  int failed_figures_ = 0;
  std::vector<std::string> figures_;
  std::vector<std::string> work_subjects_;  // Figs. 10–12, drawn after the model
  bool work_figures_pending_ = false;
  bool described_ = false;  // a robot description was given (Robot)
};

// Runs `scenario` ("all", "calibration", "repeatability", "amplitude"); the board is
// always calibrated first (it refuses trials until then), with the paper's 0.5 Hz
// sweep. The trials then run at `frequency_hz` on `threads` threads (0: one per core,
// 1: serial), each on a board of its own, and the results are the same bit for bit
// whatever the number. With a described `joint`, every board is sent its limits and
// calibrated from it (sim::CalibrationJoint), as `mjc calibrate --robot` and `mjc
// trial --robot` do. Returns the exit status.
int Run(const std::string& scenario, const plant::PlantParams& robot,
        const std::vector<plant::PlantParams>& subjects, const ControlConfig& config,
        std::uint64_t seed, int threads, double frequency_hz, Report& report,
        const Joint& joint = {});

}  // namespace mjc::paper
