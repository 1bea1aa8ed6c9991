// mjc-paper --scenario sweep (sim_host/paper/sweep.h): the grid file's refusals, a
// point's numbers against the same trial run directly on a board of the test's own,
// resume, shards and their merge, and --shard's parsing.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <numbers>
#include <string>
#include <vector>

#include "mjc/host/board_client.h"
#include "mjc/host/calibration_io.h"
#include "mjc/host/report.h"
#include "mjc/sim/bus_board.h"
#include "mjc/sim/scenarios.h"
#include "sweep.h"

namespace mjc::paper {
namespace {

namespace fs = std::filesystem;

// Four short points: two attachment stiffnesses by two slacks (two robot variants),
// three cycles at 1 Hz; a heatmap over the two.
constexpr const char* kGrid = R"({
  "subject": "subject1", "repetitions": 3, "seed": 7,
  "axes": {"stiffness_Nm_per_rad": [3.0, 6.0], "frequency_hz": [1.0],
           "cable_slack_deg": [1.5, 3.0]},
  "maps": [["stiffness_Nm_per_rad", "cable_slack_deg"]]
})";

// The scratch folders, removed when the process ends.
struct ScratchFolders {
  std::vector<fs::path> paths;
  ~ScratchFolders() {
    std::error_code ignored;
    for (const fs::path& p : paths) fs::remove_all(p, ignored);
  }
};
ScratchFolders scratch_folders;

// A folder of this process's own (others may run these tests on the machine at once).
fs::path Scratch(const std::string& name) {
  const fs::path p = fs::path(::testing::TempDir()) /
                     ("mjc_sweep_" + std::to_string(::getpid()) + "_" + name);
  fs::remove_all(p);
  scratch_folders.paths.push_back(p);
  return p;
}

std::string Text(const fs::path& p) {
  return host::ReadFileText(p).value_or("<missing>");
}

SweepPlan Plan(const char* grid = kGrid, bool noise = true) {
  SweepSettings settings;
  settings.noise = noise;
  return PlanSweep(ParseSweepGrid(grid, "grid"), settings);
}

int RunPlan(const SweepPlan& plan, const fs::path& out, Shard shard = {},
            int threads = 2) {
  SweepRunOptions o;
  o.out = out;
  o.shard = shard;
  o.threads = threads;
  o.quiet = true;
  return RunSweep(plan, o);
}

// What the summary shows, figures aside (their PNG bytes are gnuplot's).
std::vector<std::string> Summary(const fs::path& out) {
  return {Text(out / "sweep.csv"), Text(out / "sweep.md"),
          Text(out / "map_stiffness_Nm_per_rad__cable_slack_deg.dat")};
}

std::string Refusal(const std::string& grid) {
  try {
    (void)ParseSweepGrid(grid, "g.json");
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "accepted";
}

TEST(PaperSweepGrid, RefusesBadFilesNamingTheKeyAndRange) {
  const std::string axes = R"("axes": {"amplitude_deg": [10]})";
  EXPECT_EQ(Refusal("{" + axes + R"(, "sed": 1})"),
            "g.json: unknown key 'sed' (known: robot, subject, repetitions, seed, axes, "
            "maps)");
  EXPECT_NE(Refusal(R"({"axes": {"stifness_Nm_per_rad": [1]}})")
                .find("unknown axis 'axes.stifness_Nm_per_rad'"),
            std::string::npos);
  EXPECT_EQ(Refusal(R"({"axes": {"frequency_hz": [0.5, 3]}})"),
            "g.json: 'axes.frequency_hz[1]' = 3 is outside 0.25 to 2 Hz");
  EXPECT_EQ(Refusal(R"({"axes": {"damping_Nm_s_per_rad": []}})"),
            "g.json: 'axes.damping_Nm_s_per_rad' must be a non-empty list of values");
  EXPECT_EQ(Refusal(R"({"axes": {"preload_Nm": ["0.1"]}})"),
            "g.json: 'axes.preload_Nm[0]' = \"0.1\" is not a number (-1 to 1 N·m)");
  EXPECT_EQ(Refusal(R"({"axes": {"model": ["maxwell"]}})"),
            "g.json: 'axes.model[0]' = \"maxwell\" is not \"kelvin_voigt\" or "
            "\"standard_linear_solid\"");
  EXPECT_EQ(
      Refusal("{" + axes + R"(, "repetitions": 2})"),
      "g.json: 'repetitions' = 2 must be an integer from 3 to 50 (cycles per trial)");
  EXPECT_EQ(Refusal("{" + axes + R"(, "seed": -1})"),
            "g.json: 'seed' = -1 must be an integer from 0 to 2^64 - 1");
  EXPECT_EQ(Refusal(R"({"axes": {"spring_rate_N_per_m": [3150, 3150]}})"),
            "g.json: 'axes.spring_rate_N_per_m[1]' = 3150 repeats a value of the list");
  EXPECT_EQ(Refusal("{" + axes + R"(, "maps": [["amplitude_deg", "preload_Nm"]]})"),
            "g.json: 'maps[0]' names 'preload_Nm', not a numeric axis listed in 'axes'");
  EXPECT_EQ(Refusal(R"({"robot": 3, )" + axes + "}"),
            "g.json: 'robot' must be a parameter set's name or .json path (a non-empty "
            "string)");
  EXPECT_EQ(Refusal("[]"), "g.json: a grid is a JSON object");
  EXPECT_NE(Refusal("{").find("g.json: not JSON"), std::string::npos);
  EXPECT_EQ(Refusal("{" + axes + "}"), "accepted");
}

// A point whose plant the substep cannot integrate is refused by the plant's own check,
// naming the point and its axes, before anything runs.
TEST(PaperSweepGrid, RefusesAPointThePlantCannotRun) {
  try {
    (void)Plan(R"({"axes": {"stiffness_Nm_per_rad": [5, 900]}})");
    ADD_FAILURE() << "a 900 N·m/rad attachment at 100 µs substeps accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(
        std::string(e.what()).rfind("grid point 1 (stiffness_Nm_per_rad=900): field "
                                    "'integration.max_step_s'",
                                    0),
        0u)
        << e.what();
  }
}

TEST(PaperSweepGrid, RefusesMoreThanAHundredThousandPoints) {
  std::string list = "[";
  for (int i = 0; i < 40; ++i) list += (i ? ", " : "") + std::to_string(0.01 * (i + 1));
  list += "]";
  std::string degrees = "[";
  for (int i = 1; i <= 30; ++i) degrees += (i > 1 ? ", " : "") + std::to_string(i);
  degrees += "]";
  const std::string grid = R"({"axes": {"stiffness_Nm_per_rad": )" + list +
                           R"(, "damping_Nm_s_per_rad": )" + list +
                           R"(, "preload_Nm": )" + list + R"(, "amplitude_deg": )" +
                           degrees + R"(, "frequency_hz": [0.5, 1, 1.5, 2]}})";
  try {
    (void)Plan(grid.c_str());
    ADD_FAILURE() << "a grid of 7,680,000 points accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()),
              "the grid has more than 100000 points (the product of its axes' lengths): "
              "split it");
  }
}

TEST(PaperSweepGrid, ShardIsIOverN) {
  std::string why;
  EXPECT_FALSE(ParseShard("3/2", &why));
  EXPECT_NE(why.find("the index must be 0 to n - 1"), std::string::npos) << why;
  EXPECT_FALSE(ParseShard("0/0", &why));
  EXPECT_FALSE(ParseShard("x", &why));
  EXPECT_NE(why.find("is not i/n"), std::string::npos) << why;
  EXPECT_FALSE(ParseShard("1/", &why));
  EXPECT_FALSE(ParseShard("-1/2", &why));
  EXPECT_FALSE(ParseShard("1/2/3", &why));
  const auto s = ParseShard("1/2", &why);
  ASSERT_TRUE(s);
  EXPECT_EQ(s->index, 1u);
  EXPECT_EQ(s->count, 2u);
}

// The sweep's point 3 (k = 6, slack 3°) against the same trial run here: the robot with
// that slack calibrated on a board of the test's own, the record uploaded to a fresh
// board with the attachment donned, sim::RunTrial. Without sensor noise, so that
// neither path's seeds matter: the windows must be the same numbers.
TEST(PaperSweep, PointEqualsTheTrialRunDirectly) {
  const SweepPlan plan = Plan(kGrid, false);
  ASSERT_EQ(plan.points.size(), 4u);
  const fs::path out = Scratch("direct");
  ASSERT_EQ(RunPlan(plan, out), 0);
  const auto point = ReadSweepPoint(out, 3);
  ASSERT_TRUE(point);

  plant::PlantParams robot = plant::LoadPlantParams("default");
  robot.sensors.joint_noise_counts = 0;
  robot.sensors.motor_noise_counts = 0;
  const double centre = 0.5 * (robot.cable.c_right_rad + robot.cable.c_left_rad);
  const double half = 1.5 * std::numbers::pi / 180.0;
  robot.cable.c_right_rad = centre + half;
  robot.cable.c_left_rad = centre - half;
  const host::RobotDescription described;  // the default joint: k = 3150 N/m, α = 1
  sim::BusBoard calibrating(robot, app::DefaultJointConfig());
  const sim::CalibrationOutcome cal =
      sim::RunCalibration(calibrating, sim::PaperCalibrationSweep(), {&described, false});
  ASSERT_TRUE(cal.uploaded) << cal.message;

  plant::PlantParams donned = robot;
  donned.interface = plant::LoadPlantParams("subject1").interface;
  donned.interface.stiffness_Nm_per_rad = 6.0;
  sim::BusBoard board(donned, app::DefaultJointConfig());
  std::string why;
  ASSERT_TRUE(board.client().Identify(nullptr, &why)) << why;
  protocol::CalibrationRecord record;
  record.backlash = cal.record.backlash;
  record.sea_stiffness = cal.record.sea_stiffness;
  record.joint_zero_count = cal.record.joint_zero_count;
  const auto isotp = board.Connect();
  const host::UploadOutcome sent =
      host::UploadCalibration(board.client(), *isotp, record, 1000, &why);
  ASSERT_EQ(sent.status, host::UploadStatus::kAnswered) << why;
  ASSERT_EQ(sent.result, protocol::CalibrationResult::kAccepted);
  const sim::TrialOutcome direct =
      sim::RunTrial(board, sim::PaperSine(25.0, 3, 1.0), false);

  ASSERT_FALSE(direct.faulted) << direct.fault;
  const auto& got = point->trial.windows;
  ASSERT_EQ(got.size(), direct.windows.size());
  ASSERT_GE(got.size(), 5u);
  for (std::size_t i = 0; i < got.size(); ++i) {
    const sim::WindowOutcome& a = got[i];
    const sim::WindowOutcome& b = direct.windows[i];
    EXPECT_EQ(a.motion, b.motion);
    EXPECT_EQ(a.repetition, b.repetition);
    EXPECT_EQ(a.load, b.load) << i;
    EXPECT_EQ(a.unload, b.unload) << i;
    EXPECT_EQ(a.eta, b.eta) << i;
    EXPECT_EQ(a.truth_load, b.truth_load) << i;
    EXPECT_EQ(a.truth_unload, b.truth_unload) << i;
    EXPECT_EQ(a.truth_eta, b.truth_eta) << i;
    EXPECT_EQ(a.fit_valid, b.fit_valid) << i;
    EXPECT_EQ(a.stiffness, b.stiffness) << i;
    EXPECT_EQ(a.damping, b.damping) << i;
  }
  EXPECT_EQ(point->trial.power_rmse_W, direct.power_rmse_W);
  EXPECT_EQ(point->trial.truth_peak_power_W, direct.truth_peak_power_W);
  EXPECT_EQ(point->truth.stiffness, 6.0);

  // The summary row: η the mean of the three analysed flexions (all three of three).
  double eta = 0;
  int n = 0;
  for (const sim::WindowOutcome& w : direct.windows) {
    if (w.motion != Motion::kFlexion) continue;
    eta += w.eta;
    ++n;
  }
  ASSERT_EQ(n, 3);
  const std::string csv = Text(out / "sweep.csv");
  const std::string row = csv.substr(csv.find("\n3,") + 1);
  std::vector<std::string> cells;
  for (std::size_t from = 0;;) {
    const std::size_t comma = row.find_first_of(",\n", from);
    cells.push_back(row.substr(from, comma - from));
    if (row[comma] == '\n') break;
    from = comma + 1;
  }
  // index, the nine axes, flexions, eta_pct
  ASSERT_GT(cells.size(), 11u);
  EXPECT_EQ(cells[1], "6");
  EXPECT_EQ(cells[9], "3");
  EXPECT_EQ(cells[10], "3");
  EXPECT_NEAR(std::stod(cells[11]), eta / n, 1e-6 * std::fabs(eta / n));
}

TEST(PaperSweep, ResumeRerunsOnlyTheMissingPoint) {
  const SweepPlan plan = Plan();
  const fs::path out = Scratch("resume");
  ASSERT_EQ(RunPlan(plan, out), 0);
  const std::vector<std::string> first = Summary(out);
  ASSERT_NE(first[0].find("\n3,"), std::string::npos);
  const std::string kept = Text(out / "points/p00001.json");
  const auto kept_time = fs::last_write_time(out / "points/p00001.json");
  fs::remove(out / "points/p00002.csv");

  ::testing::internal::CaptureStderr();
  ASSERT_EQ(RunPlan(plan, out), 0);
  const std::string said = ::testing::internal::GetCapturedStderr();
  EXPECT_NE(said.find("3 resumed from"), std::string::npos) << said;
  EXPECT_NE(said.find("1 to run"), std::string::npos) << said;
  EXPECT_NE(said.find("sweep: 1 trials"), std::string::npos) << said;
  EXPECT_EQ(fs::last_write_time(out / "points/p00001.json"), kept_time);
  EXPECT_EQ(Text(out / "points/p00001.json"), kept);
  EXPECT_TRUE(fs::exists(out / "points/p00002.csv"));
  EXPECT_EQ(Summary(out), first);

  // Another grid in the same folder is refused, and the folder left as it was.
  const SweepPlan other = Plan(R"({"subject": "subject1", "repetitions": 3,
      "axes": {"stiffness_Nm_per_rad": [3.0], "frequency_hz": [1.0]}})");
  EXPECT_NE(other.digest, plan.digest);
  try {
    (void)RunPlan(other, out);
    ADD_FAILURE() << "another grid's folder accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("holds a sweep of another grid"),
              std::string::npos)
        << e.what();
  }
  EXPECT_EQ(Summary(out), first);
}

TEST(PaperSweep, ShardsMergedEqualTheWholeRunOnOneThread) {
  const SweepPlan plan = Plan();
  const fs::path whole = Scratch("whole"), a = Scratch("shard0"), b = Scratch("shard1"),
                 merged = Scratch("merged");
  // The whole run on one thread, the shards on two: neither may change a number.
  ASSERT_EQ(RunPlan(plan, whole, {}, 1), 0);
  ASSERT_EQ(RunPlan(plan, a, {0, 2}), 0);
  ASSERT_EQ(RunPlan(plan, b, {1, 2}), 0);
  EXPECT_TRUE(fs::exists(a / "points/p00002.json"));
  EXPECT_FALSE(fs::exists(a / "points/p00001.json"));
  EXPECT_FALSE(fs::exists(a / "sweep.csv"));  // a shard alone has no summary

  // One shard alone: the missing points named, nothing written.
  try {
    (void)MergeSweeps({a}, merged, true);
    ADD_FAILURE() << "a merge with points missing accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()),
              "2 of 4 points are in none of the folders (1, 3): run their shards first");
  }
  EXPECT_FALSE(fs::exists(merged));

  ASSERT_EQ(MergeSweeps({a, b}, merged, true), 0);
  EXPECT_EQ(Summary(merged), Summary(whole));
  for (std::size_t i = 0; i < 4; ++i) {
    for (const char* ext : {".csv", ".json"}) {
      const std::string name = "points/p0000" + std::to_string(i) + ext;
      EXPECT_EQ(Text(merged / name), Text(whole / name)) << name;
    }
  }

  // Shards of different grids are refused.
  const fs::path c = Scratch("othergrid");
  ASSERT_EQ(RunPlan(Plan(R"({"subject": "subject1", "repetitions": 3, "seed": 8,
      "axes": {"stiffness_Nm_per_rad": [3.0], "frequency_hz": [1.0]}})"),
                    c),
            0);
  try {
    (void)MergeSweeps({a, c}, Scratch("merged2"), true);
    ADD_FAILURE() << "shards of different grids merged";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("the shards' grids differ"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace mjc::paper
