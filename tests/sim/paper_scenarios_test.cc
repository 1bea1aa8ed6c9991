// The simulated board against plant ground truth, closed loop: the unmodified firmware
// application drives the plant through hal/sim, and every figure is checked against
// the plant's own interface power and energy (which the firmware never sees). Sensor
// noise on, as in the paper scenarios; every seed constant.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <vector>

#include "mjc/plant/params.h"
#include "mjc/sim/scenarios.h"

namespace {

using namespace mjc;
using namespace mjc::sim;

constexpr double kDeg = std::numbers::pi / 180.0;
constexpr double kPaperStep_s = 100e-6;  // mjc-paper's substep: one a 10 kHz tick

plant::PlantParams Robot(double max_step_s = kPaperStep_s) {
  plant::PlantParams p = plant::LoadPlantParams("default");
  p.integration.max_step_s = max_step_s;
  return p;
}

// A calibrated board with `subject`'s interface donned.
struct Bench {
  explicit Bench(const plant::PlantParams& robot)
      : board(robot, app::DefaultJointConfig()) {
    calibration = RunCalibration(board, PaperCalibrationSweep());
  }
  BusBoard board;
  CalibrationOutcome calibration;
};

TEST(SimCalibration, RecoversSeveralSlackPairsWithinGoal) {
  // (c_r, c_l) in degrees: the default, asymmetric, offset, and a wide one.
  const double pairs[][2] = {{1.1, -0.9}, {2.0, -0.5}, {0.3, -2.2}, {2.5, 1.0}};
  for (const auto& pair : pairs) {
    plant::PlantParams robot = Robot();
    robot.cable.c_right_rad = pair[0] * kDeg;
    robot.cable.c_left_rad = pair[1] * kDeg;
    Bench bench(robot);
    const CalibrationOutcome& cal = bench.calibration;
    SCOPED_TRACE(::testing::Message()
                 << "c_r " << pair[0] << "°, c_l " << pair[1] << "°");
    ASSERT_TRUE(cal.uploaded) << cal.message << " / " << cal.fit.message;
    EXPECT_LE(std::fabs(cal.error_right_deg), 0.05);
    EXPECT_LE(std::fabs(cal.error_left_deg), 0.05);
    EXPECT_TRUE(bench.board.app().calibrated());
    std::printf(
        "[ calib    ] c_r %+.3f° err %+.4f°, c_l %+.3f° err %+.4f°, fit %.1f ms\n",
        pair[0], cal.error_right_deg, pair[1], cal.error_left_deg, cal.fit.elapsed_ms);
  }
}

// The same sweep on a board that sat idle for 100 ms first, as a lab's board sits before
// `mjc calibrate` (and as the tools' identification of a node takes). For the wide pair
// (2.5°, 1.0°) the fit's global stage then settles in the basin of no lag and a wider
// band (c_r +0.066°, c_l −0.067°, lag 0.02 ms, RMS 0.044° against 0.023° at the right
// fit); the local stage's starts spread over the lag's range (host::FitBacklash) find
// the right basin from there. This test failed before them.
TEST(SimCalibration, RecoversAWidePairAfterTheBoardSatIdle) {
  plant::PlantParams robot = Robot();
  robot.cable.c_right_rad = 2.5 * kDeg;
  robot.cable.c_left_rad = 1.0 * kDeg;
  BusBoard board(robot, app::DefaultJointConfig());
  board.Run(board.tick_hz() / 10);
  const CalibrationOutcome cal = RunCalibration(board, PaperCalibrationSweep());
  ASSERT_TRUE(cal.uploaded) << cal.message << " / " << cal.fit.message;
  EXPECT_LE(std::fabs(cal.error_right_deg), 0.05);
  EXPECT_LE(std::fabs(cal.error_left_deg), 0.05);
}

TEST(SimTrial, BoardMatchesPlantTruthAcrossAmplitudes) {
  Bench bench(Robot());
  ASSERT_TRUE(bench.calibration.uploaded);
  const plant::PlantParams subject = plant::LoadPlantParams("subject1");
  const SubjectSweep sweep =
      RunAmplitudeSweep(bench.board, subject, {6, 8, 11, 15, 20, 25}, nullptr, 0, 1);
  ASSERT_EQ(sweep.points.size(), 6u);
  double previous_load = 0, previous_net = 0, previous_unload = 0;
  for (const AmplitudePoint& p : sweep.points) {
    SCOPED_TRACE(::testing::Message() << p.amplitude_deg << "°");
    ASSERT_EQ(p.flexions.size(), 3u);  // the middle three of five
    for (const WindowOutcome& w : p.flexions) {
      // Energy per window within 2 % of the loading energy; η within 1 point.
      EXPECT_NEAR(w.load, w.truth_load, 0.02 * w.truth_load);
      EXPECT_NEAR(w.unload, w.truth_unload, 0.02 * w.truth_load);
      EXPECT_NEAR(w.eta, w.truth_eta, 1.0);
    }
    // Instantaneous power within 2 % of peak at every amplitude. At 6–8° the joint
    // swings only ±29–38 counts of the 14-bit encoder: the plain 50 ms slope was near
    // 4 % there, the attachment model's residual over 100 ms is near 1 %
    // (attachment_model.h).
    EXPECT_LE(p.power_rmse_pct_peak, 2.0);
    // The paper's trends (Figs. 10–12), from the board's estimate.
    EXPECT_GT(p.load.mean, previous_load);
    EXPECT_GT(p.net.mean, previous_net);
    EXPECT_LT(p.unload.mean, previous_unload);
    previous_load = p.load.mean;
    previous_net = p.net.mean;
    previous_unload = p.unload.mean;
  }
  // At 25° the paper's magnitudes: η in the 40–50 % band.
  EXPECT_GT(sweep.points.back().eta.mean, 40.0);
  EXPECT_LT(sweep.points.back().eta.mean, 50.0);
}

TEST(SimTrial, ElasticInterfaceReadsNoLoss) {
  Bench bench(Robot());
  ASSERT_TRUE(bench.calibration.uploaded);
  plant::PlantParams subject = plant::LoadPlantParams("subject1");
  subject.interface.damping_Nm_s_per_rad = 0.0;  // purely elastic
  bench.board.plant().SetInterface(subject.interface);
  for (double amplitude : {11.0, 25.0}) {
    const TrialOutcome t = RunTrial(bench.board, PaperSine(amplitude), false);
    ASSERT_FALSE(t.faulted) << t.fault;
    const auto flexions = host::AnalysedFlexions(t.windows, 5);
    ASSERT_EQ(flexions.size(), 3u);
    for (const WindowOutcome* w : flexions) {
      EXPECT_LE(std::fabs(w->eta), 1.0) << amplitude << "°: board η " << w->eta;
      EXPECT_LE(std::fabs(w->truth_eta), 1.0)
          << amplitude << "°: truth η " << w->truth_eta;
    }
  }
}

// Tables II–III's normalised errors, from points built by hand (no simulation): the
// RMSE over the reference's range where that range stands above the noise floor, and
// no percentage (NaN, with the range and the floor) where it does not — the net work of
// an elastic attachment, ~0 at every amplitude.
AmplitudePoint HandPoint(double amplitude_deg, double load, double truth_load, double net,
                         double truth_net, double se) {
  AmplitudePoint p;
  p.amplitude_deg = amplitude_deg;
  p.load = {3, load, se * std::sqrt(3.0), se};
  p.unload = {3, -(load - net), 0, 0};
  p.net = {3, net, se * std::sqrt(3.0), se};
  p.truth_load = {3, truth_load, 0, 0};
  p.truth_unload = {3, -(truth_load - truth_net), 0, 0};
  p.truth_net = {3, truth_net, 0, 0};
  return p;
}

TEST(SimTables, ANetWorkWithoutRangeIsNotNormalised) {
  // An elastic attachment's work (J): loading grows with amplitude, net stays at 3 µJ
  // within 0.2 µJ; the board's net a few µJ off.
  const std::vector<AmplitudePoint> points = {
      HandPoint(6, 0.245e-3, 0.245e-3, 0.003e-3, 0.0030e-3, 0.5e-6),
      HandPoint(15, 2.014e-3, 2.011e-3, 0.006e-3, 0.0031e-3, 0.5e-6),
      HandPoint(25, 5.926e-3, 5.915e-3, 0.013e-3, 0.0032e-3, 1.0e-6)};
  const SubjectSweep s = SummariseSweep("elastic", points);
  // The floor: 1 % of the largest loading work (59.15 µJ) beats 2 SE (2 µJ).
  EXPECT_DOUBLE_EQ(s.noise_floor_J, 0.01 * 5.915e-3);
  EXPECT_NEAR(s.range_net, 0.0002e-3, 1e-12);
  EXPECT_TRUE(std::isnan(s.nrmse_net)) << s.nrmse_net;
  // The RMSE itself is still given.
  const double net_rmse =
      std::sqrt((0.0 + std::pow(0.0029e-3, 2) + std::pow(0.0098e-3, 2)) / 3);
  EXPECT_NEAR(s.rmse_net, net_rmse, 1e-12);
  // The loading work's range is 5.67 mJ: normalised, by hand.
  const double load_rmse =
      std::sqrt((0.0 + std::pow(0.003e-3, 2) + std::pow(0.011e-3, 2)) / 3);
  EXPECT_NEAR(s.nrmse_load, 100 * load_rmse / (5.915e-3 - 0.245e-3), 1e-9);
}

TEST(SimTables, TheBoardsScatterSetsTheFloorWhenItIsLarger) {
  // A range of 40 µJ against the board's SE of 25 µJ at one amplitude (2 SE = 50 µJ):
  // not judged, though it is 6 % of the loading work.
  const std::vector<AmplitudePoint> points = {
      HandPoint(6, 0.30e-3, 0.30e-3, 0.10e-3, 0.10e-3, 1e-6),
      HandPoint(25, 0.65e-3, 0.66e-3, 0.15e-3, 0.14e-3, 25e-6)};
  const SubjectSweep s = SummariseSweep("scattered", points);
  EXPECT_DOUBLE_EQ(s.noise_floor_J, 2 * 25e-6);
  EXPECT_TRUE(std::isnan(s.nrmse_net));
  EXPECT_TRUE(std::isfinite(s.nrmse_load));  // range 360 µJ
}

TEST(SimTrial, TheVelocityModelTakesTheBoardsOwnFitOfTheAttachment) {
  // A prior a third of subject 2's attachment (k 1.8, b 0.1 against 5.5, 0.29: a model
  // that far off doubles the plain slope's power error, SIGNAL_CHAIN.md). The
  // calibration sweep, robot alone, leaves it; a trial's windows replace it with the
  // board's fit, and the next trial's power is within 2 % of its peak at 6°.
  ControlConfig config = app::DefaultJointConfig();
  const AttachmentParams prior{Stiffness::Quantize(1.8), Damping::Quantize(0.1)};
  config.attachment_prior = prior;
  BusBoard board(Robot(), config);
  ASSERT_TRUE(RunCalibration(board, PaperCalibrationSweep()).uploaded);
  EXPECT_EQ(board.app().control().attachment().stiffness, prior.stiffness);
  EXPECT_EQ(board.app().control().attachment().damping, prior.damping);

  const plant::PlantParams subject = plant::LoadPlantParams("subject2");
  board.plant().SetInterface(subject.interface);
  const TrialOutcome first = RunTrial(board, PaperSine(11), false);
  ASSERT_FALSE(first.faulted) << first.fault;
  const AttachmentParams& fitted = board.app().control().attachment();
  EXPECT_NEAR(fitted.stiffness.ToDouble(), subject.interface.stiffness_Nm_per_rad,
              0.03 * subject.interface.stiffness_Nm_per_rad);
  EXPECT_NEAR(fitted.damping.ToDouble(), subject.interface.damping_Nm_s_per_rad,
              0.03 * subject.interface.damping_Nm_s_per_rad);

  const TrialOutcome small = RunTrial(board, PaperSine(6), false);
  ASSERT_FALSE(small.faulted) << small.fault;
  ASSERT_GT(small.truth_peak_power_W, 0.0);
  const double power_pct = 100.0 * small.power_rmse_W / small.truth_peak_power_W;
  EXPECT_LE(power_pct, 2.0);
  std::printf(
      "[ model    ] fitted k %.3f b %.4f (subject 2: 5.5, 0.29); 6° power %.2f %%\n",
      fitted.stiffness.ToDouble(), fitted.damping.ToDouble(), power_pct);
}

TEST(SimTrial, ResultsDoNotDependOnThePlantSubstep) {
  // mjc-paper integrates at 100 µs, one implicit substep a tick, where the cable
  // side's contact and bristle modes (≈ 30,000 rad/s) are not resolved; at 10 µs they
  // are (h·ω ≤ 0.3). The board's window energies must agree within 0.2 %, so the
  // unresolved fast modes change no table.
  std::vector<double> loads[2];
  const double steps[] = {10e-6, kPaperStep_s};
  for (int i = 0; i < 2; ++i) {
    Bench bench(Robot(steps[i]));
    ASSERT_TRUE(bench.calibration.uploaded);
    bench.board.plant().SetInterface(plant::LoadPlantParams("subject2").interface);
    const TrialOutcome t = RunTrial(bench.board, PaperSine(20), false);
    for (const WindowOutcome* w : host::AnalysedFlexions(t.windows, 5))
      loads[i].push_back(w->truth_load);
  }
  ASSERT_EQ(loads[0].size(), 3u);
  ASSERT_EQ(loads[1].size(), 3u);
  for (std::size_t k = 0; k < 3; ++k)
    EXPECT_NEAR(loads[1][k], loads[0][k], 0.002 * loads[0][k]);
}

// Every number a trial outcome holds, in order: two outcomes are the same iff these are.
std::vector<double> Flatten(const TrialOutcome& t) {
  std::vector<double> v = {t.power_rmse_W, t.truth_peak_power_W,
                           static_cast<double>(t.ticks), t.faulted ? 1.0 : 0.0};
  for (const WindowOutcome& w : t.windows) {
    v.insert(v.end(), {static_cast<double>(w.motion), static_cast<double>(w.repetition),
                       w.load, w.unload, w.net, w.eta, w.truth_load, w.truth_unload,
                       w.truth_net, w.truth_eta, w.peak_fraction});
    v.insert(v.end(), w.profile.begin(), w.profile.end());
    v.insert(v.end(), w.truth_profile.begin(), w.truth_profile.end());
  }
  for (const TraceRow& r : t.trace) {
    v.insert(v.end(),
             {r.t, r.setpoint, r.motor, r.joint, r.torque, r.power, r.truth_power});
  }
  return v;
}

TEST(SimTrial, IndependentTrialsAreTheSameOnAnyNumberOfThreads) {
  Bench bench(Robot());
  ASSERT_TRUE(bench.calibration.uploaded);
  const plant::PlantParams s1 = plant::LoadPlantParams("subject1");
  const plant::PlantParams s2 = plant::LoadPlantParams("subject2");
  const std::vector<TrialSpec> specs = {
      {s1.interface, 25, true, 11, "s1 25°"},
      {s2.interface, 11, false, 12, "s2 11°"},
      {plant::Redon(s1, 3).interface, 25, false, 13, "s1 re-donned"},
      {s1.interface, 25, false, 14, "s1 25°, other noise"},
      {s2.interface, 6, false, 15, "s2 6°"},
  };
  int calls = 0;
  const auto serial =
      RunTrials(Robot(), app::DefaultJointConfig(), bench.calibration.record, specs, 1,
                [&calls](const std::string&, double) { ++calls; });
  EXPECT_EQ(calls, 5);
  const auto parallel = RunTrials(Robot(), app::DefaultJointConfig(),
                                  bench.calibration.record, specs, 4, nullptr);
  ASSERT_EQ(serial.size(), specs.size());
  ASSERT_EQ(parallel.size(), specs.size());
  for (std::size_t i = 0; i < specs.size(); ++i) {
    SCOPED_TRACE(specs[i].label);
    ASSERT_FALSE(serial[i].faulted) << serial[i].fault;
    EXPECT_EQ(host::AnalysedFlexions(serial[i].windows, 5).size(), 3u);
    EXPECT_EQ(Flatten(parallel[i]), Flatten(serial[i]));  // bit for bit
  }
  EXPECT_FALSE(serial[0].trace.empty());
  // The runs are not copies of one another: another noise seed is another outcome.
  EXPECT_NE(Flatten(serial[3]), Flatten(serial[0]));
  EXPECT_EQ(serial[3].ticks, serial[0].ticks);
}

// A sensor fault injected in the plant mid-trial disables the bridge in the tick whose
// sample carries it, and the board reports it.
void ExpectSameTickStop(plant::SensorFaultKind kind, Fault expected,
                        std::int32_t jump = 0) {
  Bench bench(Robot());
  ASSERT_TRUE(bench.calibration.uploaded);
  bench.board.plant().SetInterface(plant::LoadPlantParams("subject1").interface);
  app::JointApp& app = bench.board.app();
  ASSERT_EQ(app.StartTrial(PaperSine(25)).result, app::CommandOutcomeCode::kAccepted);
  for (int i = 0; i < 8000; ++i) bench.board.board().Tick();  // mid-flexion
  ASSERT_EQ(app.state(), app::BoardState::kRunning);
  ASSERT_TRUE(bench.board.board().io().bridge_enabled());
  bench.board.plant().InjectFault({kind, 0, jump});
  bench.board.board().Tick();
  EXPECT_FALSE(bench.board.board().io().bridge_enabled());
  EXPECT_EQ(bench.board.board().io().duty(), 0.0);
  EXPECT_EQ(app.state(), app::BoardState::kFault);
  EXPECT_EQ(app.last().raised, expected);
}

TEST(SimFaults, JointParityStopsInTheSameTick) {
  ExpectSameTickStop(plant::SensorFaultKind::kJointParity, Fault::kJointParity);
}
TEST(SimFaults, JointErrorFlagStopsInTheSameTick) {
  ExpectSameTickStop(plant::SensorFaultKind::kJointErrorFlag, Fault::kJointErrorFlag);
}
TEST(SimFaults, JointJumpStopsInTheSameTick) {
  // 100 counts (0.038 rad) in one tick: far beyond any real joint motion.
  ExpectSameTickStop(plant::SensorFaultKind::kJointJump, Fault::kJointJump, 100);
}

TEST(SimFaults, StuckJointEncoderIsCaught) {
  // A frozen frame is only implausible once the motor has travelled stuck_motor_travel
  // (0.6 rad) from where the count froze: a joint blocked by a stiff hand may stand
  // still while the motor winds the springs, so a shorter bound would trip on healthy
  // boards. Frozen at the flexion peak (+25°), it is caught on the way down to −25°,
  // within half a cycle, and the bridge goes off in the detecting tick.
  Bench bench(Robot());
  ASSERT_TRUE(bench.calibration.uploaded);
  bench.board.plant().SetInterface(plant::LoadPlantParams("subject1").interface);
  app::JointApp& app = bench.board.app();
  ASSERT_EQ(app.StartTrial(PaperSine(25)).result, app::CommandOutcomeCode::kAccepted);
  // 1.5 s of rest, then a quarter cycle: the first flexion peak.
  for (int i = 0; i < 15000 + 5000; ++i) bench.board.board().Tick();
  bench.board.plant().InjectFault({plant::SensorFaultKind::kJointStuck, 0, 0});
  int ticks = 0;
  while (app.state() != app::BoardState::kFault && ticks < 10000) {
    bench.board.board().Tick();
    ++ticks;
  }
  EXPECT_EQ(app.last().raised, Fault::kJointStuck);
  EXPECT_FALSE(bench.board.board().io().bridge_enabled());
  EXPECT_LT(ticks, 10000);
  std::printf("[ fault    ] stuck joint encoder caught after %d ticks\n", ticks);
}

}  // namespace
