// Orchestration and output of mjc-paper: calibrates a simulated board, runs the
// scenarios' trials (on threads, each on a board of its own) and turns their outcomes
// into printed tables, CSV, JSON and gnuplot figures.
#pragma once

#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "mjc/plant/params.h"
#include "mjc/sim/scenarios.h"

namespace mjc::paper {

class Report {
 public:
  // `frequency_hz`: the trials' drive frequency, for titles and results.json.
  Report(std::filesystem::path out, bool quiet,
         double frequency_hz = sim::kPaperFrequencyHz);

  void Progress(const std::string& stage, double fraction);
  void Calibration(const sim::CalibrationOutcome& cal);
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
};

// Runs `scenario` ("all", "calibration", "repeatability", "amplitude"); the board is
// always calibrated first (it refuses trials until then), with the paper's 0.5 Hz
// sweep. The trials then run at `frequency_hz` on `threads` threads (0: one per core,
// 1: serial), each on a board of its own, and the results are the same bit for bit
// whatever the number. Returns the exit status.
int Run(const std::string& scenario, const plant::PlantParams& robot,
        const std::vector<plant::PlantParams>& subjects, const ControlConfig& config,
        std::uint64_t seed, int threads, double frequency_hz, Report& report);

}  // namespace mjc::paper
