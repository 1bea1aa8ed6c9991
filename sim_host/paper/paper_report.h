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
  Report(std::filesystem::path out, bool quiet);

  void Progress(const std::string& stage, double fraction);
  void Calibration(const sim::CalibrationOutcome& cal);
  void Trial(const sim::TrialOutcome& trial, double amplitude_deg);
  void Repeatability(const sim::RepeatabilityOutcome& rep, double amplitude_deg);
  void Amplitude(const std::vector<sim::SubjectSweep>& sweeps);
  // Writes results.json and tables.md; returns the number of figures that failed.
  int Finish(double wall_s, double simulated_s);

  const std::filesystem::path& out() const { return out_; }

 private:
  void Print(const std::string& text);
  void Figure(const std::string& name, const std::string& script);

  std::filesystem::path out_;
  bool quiet_;
  std::string tables_;
  nlohmann::json json_;
  int failed_figures_ = 0;
  std::vector<std::string> figures_;
};

// Runs `scenario` ("all", "calibration", "repeatability", "amplitude"); the board is
// always calibrated first (it refuses trials until then). The trials then run on
// `threads` threads (0: one per core, 1: serial), each on a board of its own, and the
// results are the same bit for bit whatever the number. Returns the exit status.
int Run(const std::string& scenario, const plant::PlantParams& robot,
        const std::vector<plant::PlantParams>& subjects, const ControlConfig& config,
        std::uint64_t seed, int threads, Report& report);

}  // namespace mjc::paper
