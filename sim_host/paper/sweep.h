// mjc-paper --scenario sweep: the design and control space the paper proposes to explore
// in simulation (the attachment's stiffness, damping, model and preload; the trial's
// amplitude and frequency; the robot's spring rate and cable slack), a grid of points,
// each a full trial on a calibrated simulated board (sim::RunTrials, as the paper's
// scenarios run theirs), judged against the plant's truth. The grid file's format, the
// output folder and resume, shards and merge are described in sim_host/README.md
// ("Design-space sweep").
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "mjc/app/joint_config.h"
#include "mjc/plant/params.h"
#include "mjc/sim/scenarios.h"

namespace mjc::paper {

// The grid's axes, in the order of its Cartesian product (the last varies fastest).
enum class SweepAxis : std::uint8_t {
  kStiffness = 0,     // the attachment's k, N·m/rad
  kDamping,           // its b, N·m·s/rad
  kModel,             // 0: Kelvin–Voigt, 1: standard linear solid
  kMaxwellStiffness,  // the SLS's k_2, N·m/rad (no effect on Kelvin–Voigt points)
  kPreload,           // τ_0, N·m
  kAmplitude,         // the trial's amplitude, degrees
  kFrequency,         // its drive frequency, Hz
  kSpringRate,        // the robot's SEA spring rate k (each of two springs), N/m
  kCableSlack,        // the robot's cable slack c_r − c_l, degrees
};
inline constexpr std::size_t kSweepAxes = 9;

struct SweepAxisInfo {
  std::string_view key;   // in the grid file and the CSV header
  std::string_view unit;  // in messages
  double min, max;        // the checked range (the model axis: by name)
};
const SweepAxisInfo& AxisInfo(SweepAxis axis);

struct SweepGrid {
  std::string robot = "default";     // base robot parameter set (name or .json path)
  std::string subject = "subject1";  // base subject (its interface)
  std::uint16_t repetitions = 5;     // cycles per trial, [3, 50]
  std::uint64_t seed = 1;            // of the sensor noise
  // Each axis' values; empty: the axis is absent, its value is the base sets'.
  std::array<std::vector<double>, kSweepAxes> values;
  // Heatmaps: pairs of numeric axes (x, y).
  std::vector<std::array<SweepAxis, 2>> maps;
};

// Parses a grid file's text strictly; throws std::runtime_error with one line naming
// `source`, the key and the accepted range or values.
SweepGrid ParseSweepGrid(std::string_view text, std::string_view source);

// The settings a point's numbers depend on besides the grid (in the digest too).
struct SweepSettings {
  bool noise = true;
  double max_step_us = 100.0;
  int velocity_window = 0;  // 0: the board's default
};

// One point of the product.
struct SweepPoint {
  std::size_t index = 0;
  std::array<double, kSweepAxes> value{};
  std::size_t variant = 0;  // which robot variant (spring rate, slack) it runs on
  plant::InterfaceParams interface;
};

// The grid resolved against its base parameter sets.
struct SweepPlan {
  SweepGrid grid;
  SweepSettings settings;
  plant::PlantParams robot, subject;  // as loaded (the robot with the settings applied)
  std::array<std::vector<double>, kSweepAxes> values;  // absent axes: the base value
  std::vector<SweepPoint> points;                      // the whole product, in order
  std::vector<plant::PlantParams> variants;            // robot per (spring rate, slack)
  ControlConfig config;
  std::string digest;     // 16 hex digits: the grid, the settings, the base sets
  nlohmann::json record;  // grid.json: the digest, the resolved grid
};

// Loads the base sets, builds the product and checks every point's plant
// (plant::ValidatePlantParams); throws std::runtime_error naming the point.
SweepPlan PlanSweep(const SweepGrid& grid, const SweepSettings& settings);

// "i/n" with 0 ≤ i < n; nullopt (and why) otherwise.
struct Shard {
  std::size_t index = 0, count = 1;
};
std::optional<Shard> ParseShard(std::string_view text, std::string* why);

struct SweepRunOptions {
  std::filesystem::path out;
  Shard shard;
  int threads = 0;
  bool quiet = false;
};

// Runs the shard's points not already complete in `out` (each written as it ends,
// atomically), then, unsharded, the summary. Returns the exit status; messages on
// stderr.
int RunSweep(const SweepPlan& plan, const SweepRunOptions& options);

// Joins the shards' folders into `out` (their points copied, then the summary).
// Refuses (non-zero, one line) folders of different grids or a point none holds.
int MergeSweeps(const std::vector<std::filesystem::path>& shards,
                const std::filesystem::path& out, bool quiet);

// A point's trial as written and read back (points/pNNNNN.csv and .json).
struct SweepPointResult {
  sim::TrialOutcome trial;    // windows, power RMSE and peak, ticks, fault
  sim::InterfaceTruth truth;  // TrueInterface at the point's frequency
};
std::optional<SweepPointResult> ReadSweepPoint(const std::filesystem::path& out,
                                               std::size_t index);

// The sweep's entry from main: --grid (or --merge) with the other options.
struct SweepCommand {
  std::string grid_path;
  std::vector<std::string> merge;
  std::string out;
  std::string shard;  // "" : the whole grid
  int threads = 0;
  bool quiet = false;
  SweepSettings settings;
};
int SweepMain(const SweepCommand& command);

}  // namespace mjc::paper
