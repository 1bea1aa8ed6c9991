// The paper's experiment against its model (Figs. 10–12, Tables II–III), closed loop:
// the board's measured work per flexion across the amplitude sweep against the
// simulator's prediction from the attachment the board itself identified (a
// Kelvin–Voigt interface of its mean k_i, b_i, τ_0; experiment_rig.h), for Kelvin–Voigt
// hands and for a standard linear solid, whose form the model does not share.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "experiment_rig.h"
#include "mjc/app/joint_config.h"

namespace {

using namespace mjc;
using namespace mjc::sim;

const std::vector<double> kAmplitudes = {6, 8, 11, 15, 20, 25};

TEST(SimModel, PredictionFromTheIdentifiedAttachmentAgreesWithTheBoard) {
  // Setup: a calibrated board's record; subjects 1 and 3 (the stiffest and the loosest
  // of the shipped attachments relative to their damping).
  const plant::PlantParams robot = rig::PaperRobot();
  BusBoard board(robot, app::DefaultJointConfig());
  const CalibrationOutcome cal = RunCalibration(board, PaperCalibrationSweep());
  ASSERT_TRUE(cal.uploaded) << cal.message;
  const std::vector<plant::PlantParams> subjects = {plant::LoadPlantParams("subject1"),
                                                    plant::LoadPlantParams("subject3")};

  // Exercise.
  const rig::ModelRun run = rig::RunModelAgainstBoard(
      robot, cal.record, subjects, kAmplitudes, kPaperFrequencyHz, 7, 0);

  // Verify.
  ASSERT_EQ(run.comparisons.size(), subjects.size());
  for (std::size_t s = 0; s < subjects.size(); ++s) {
    const ModelComparison& c = run.comparisons[s];
    const plant::InterfaceParams& truth = subjects[s].interface;
    SCOPED_TRACE(c.subject);
    ASSERT_EQ(c.points.size(), kAmplitudes.size());
    // The model is built from fits at ≥ 11°: three flexions at each of four amplitudes.
    EXPECT_EQ(c.identified.stiffness.n, 12u);
    // What the board identified is the plant's own attachment within the fit's 10 %
    // (interface_fit_sim_test.cc), less the bearings' b_j for the model.
    EXPECT_NEAR(c.model.stiffness_Nm_per_rad, truth.stiffness_Nm_per_rad,
                0.10 * truth.stiffness_Nm_per_rad);
    EXPECT_NEAR(c.model.damping_Nm_s_per_rad, truth.damping_Nm_s_per_rad,
                0.10 * truth.damping_Nm_s_per_rad);
    EXPECT_EQ(c.model.model, plant::InterfaceModel::kKelvinVoigt);
    // The bound: the goal, 5 % of the prediction's range, for loading,
    // unloading and net alike. What separates measurement from prediction is the
    // board's own error against its plant (each window's energies within 2 % of the
    // loading energy, paper_scenarios_test.cc) and the error of the identified k_i and
    // b_i; the subject's attachment is Kelvin–Voigt, so the model's form adds none.
    // Net work has the smallest range (about 0.44 of the loading at 25°): the board's
    // window error alone, at its 2 % bound and growing with amplitude as the work does
    // (∝ a²), would put the net's NRMSE near 4.7 %. So 5 % holds only if the board
    // keeps well inside its own bound and the identified attachment adds little;
    // measured, the net's NRMSE is about 0.2 %. Against another subject's model
    // (below) the same comparison is outside 5 %: the bound tells two shipped hands
    // apart.
    EXPECT_LE(c.nrmse_load, 5.0);
    EXPECT_LE(c.nrmse_unload, 5.0);
    EXPECT_LE(c.nrmse_net, 5.0);
    // The prediction is the model plant's truth, not the board's estimate on it: every
    // point is a number of its own, and the trends are the paper's.
    double previous_net = 0;
    for (const ModelPoint& p : c.points) {
      EXPECT_NE(p.model_load, p.load.mean);
      EXPECT_GT(p.model_net, previous_net);
      previous_net = p.model_net;
    }
    std::printf(
        "[ model    ] %s: k %.3f b %.4f τ0 %+.4f; NRMSE load %.2f%% unload %.2f%% net "
        "%.2f%% (RMSE net %.4f mJ)\n",
        c.subject.c_str(), c.model.stiffness_Nm_per_rad, c.model.damping_Nm_s_per_rad,
        c.model.preload_Nm, c.nrmse_load, c.nrmse_unload, c.nrmse_net, 1e3 * c.rmse_net);
  }
  // Subject 1's measurement (k 4.5 N·m/rad, b 0.25 N·m·s/rad) against subject 3's
  // model (k 4.0, b 0.235) is outside the bound.
  const ModelComparison crossed =
      CompareWithModel(run.measured[0], run.predicted[1], run.comparisons[1].identified,
                       run.comparisons[1].model);
  std::printf("[ model    ] subject1 against subject3's model: NRMSE net %.2f%%\n",
              crossed.nrmse_net);
  EXPECT_GT(crossed.nrmse_net, 5.0);
}

TEST(SimModel, AStandardLinearSolidHandIsPredictedAtTheFrequencyItWasIdentifiedAt) {
  // Setup: subject 1's hand with a standard linear solid attachment (k 3 N·m/rad, a
  // Maxwell arm of k_2 2.5 N·m/rad and b 0.25 N·m·s/rad, relaxing in λ = b/k_2 =
  // 0.1 s), a form the Kelvin–Voigt model does not have. At 0.5 Hz it acts as
  // k_eff = k + k_2·(ωλ)²/(1 + (ωλ)²) = 3.22 and b_eff = b/(1 + (ωλ)²) = 0.228; at
  // 2 Hz as 4.53 and 0.097.
  const plant::PlantParams robot = rig::PaperRobot();
  BusBoard board(robot, app::DefaultJointConfig());
  const CalibrationOutcome cal = RunCalibration(board, PaperCalibrationSweep());
  ASSERT_TRUE(cal.uploaded) << cal.message;
  plant::PlantParams sls = plant::LoadPlantParams("subject1");
  sls.name = "subject1-sls";
  sls.interface.model = plant::InterfaceModel::kStandardLinearSolid;
  sls.interface.stiffness_Nm_per_rad = 3.0;
  sls.interface.maxwell_stiffness_Nm_per_rad = 2.5;
  sls.interface.damping_Nm_s_per_rad = 0.25;

  // Exercise: the paper's sweep at 0.5 Hz, measured and predicted from what the board
  // identified.
  const rig::ModelRun run = rig::RunModelAgainstBoard(
      robot, cal.record, {sls}, kAmplitudes, kPaperFrequencyHz, 7, 0);

  // Verify: the board identified the hand's effective values at the drive frequency
  // (TrueInterface, checked against the complex stiffness in
  // interface_fit_sim_test.cc), and the Kelvin–Voigt model of them predicts the works
  // at that frequency within the same 5 % as for a Kelvin–Voigt hand.
  ASSERT_EQ(run.comparisons.size(), 1u);
  const ModelComparison& c = run.comparisons[0];
  const InterfaceTruth effective = TrueInterface(sls.interface, kPaperFrequencyHz);
  EXPECT_NEAR(c.model.stiffness_Nm_per_rad, effective.stiffness,
              0.10 * effective.stiffness);
  EXPECT_NEAR(c.model.damping_Nm_s_per_rad, effective.damping, 0.10 * effective.damping);
  EXPECT_LE(c.nrmse_load, 5.0);
  EXPECT_LE(c.nrmse_unload, 5.0);
  EXPECT_LE(c.nrmse_net, 5.0);
  std::printf(
      "[ model    ] SLS hand at 0.5 Hz: k %.3f b %.4f (effective %.3f, %.4f); NRMSE "
      "load %.2f%% unload %.2f%% net %.2f%%\n",
      c.model.stiffness_Nm_per_rad, c.model.damping_Nm_s_per_rad, effective.stiffness,
      effective.damping, c.nrmse_load, c.nrmse_unload, c.nrmse_net);

  // And only there: the same model against the hand driven at 2 Hz, where the Maxwell
  // arm stiffens it by 40 %, misses the works by far more than 5 %.
  plant::PlantParams model_hand = sls;
  model_hand.name = "subject1-sls-model";
  model_hand.interface = c.model;
  const std::vector<double> amplitudes = {11, 15, 20, 25};
  const rig::ModelRun fast = rig::RunModelAgainstBoard(
      robot, cal.record, {sls, model_hand}, amplitudes, 2.0, 9, 0);
  ASSERT_EQ(fast.measured.size(), 2u);
  const ModelComparison off =
      CompareWithModel(fast.measured[0], fast.measured[1], c.identified, c.model);
  std::printf(
      "[ model    ] SLS hand at 2 Hz against its 0.5 Hz model: NRMSE net %.2f%%\n",
      off.nrmse_net);
  EXPECT_GT(off.nrmse_net, 5.0);
}

TEST(SimModel, ModelIsTheMeanFitAtElevenDegreesAndAboveLessTheBearings) {
  // Setup: fits at 6° (left out: too few encoder counts for θ̇_j), two at 11° and 25°,
  // one at 25° the board could not solve (left out).
  const auto window = [](bool valid, double k, double b, double offset) {
    WindowOutcome w;
    w.fit_valid = valid;
    w.stiffness = k;
    w.damping = b;
    w.offset = offset;
    return w;
  };
  SubjectSweep sweep;
  sweep.points.resize(3);
  sweep.points[0].amplitude_deg = 6;
  sweep.points[0].flexions = {window(true, 9.0, 0.9, 0.9)};
  sweep.points[1].amplitude_deg = 11;
  sweep.points[1].flexions = {window(true, 4.0, 0.20, 0.010)};
  sweep.points[2].amplitude_deg = 25;
  sweep.points[2].flexions = {window(true, 5.0, 0.30, 0.020),
                              window(false, 7.0, 0.7, 0.7)};
  plant::PlantParams robot = rig::PaperRobot();
  robot.joint.viscous_Nm_s_per_rad = 0.004;

  // Exercise.
  const IdentifiedAttachment identified = IdentifyAttachment(sweep);
  const plant::InterfaceParams model = ModelInterface(identified, robot);

  // Verify: the means of the two fits that count; b less the robot's own bearings.
  EXPECT_EQ(identified.stiffness.n, 2u);
  EXPECT_TRUE(model.present);
  EXPECT_EQ(model.model, plant::InterfaceModel::kKelvinVoigt);
  EXPECT_NEAR(model.stiffness_Nm_per_rad, 4.5, 1e-12);
  EXPECT_NEAR(model.damping_Nm_s_per_rad, 0.25 - 0.004, 1e-12);
  EXPECT_NEAR(model.preload_Nm, 0.015, 1e-12);
  // No fit at all: no model.
  sweep.points.erase(sweep.points.begin() + 1, sweep.points.end());
  EXPECT_THROW(ModelInterface(IdentifyAttachment(sweep), robot), std::invalid_argument);
}

TEST(SimModel, ComparisonRefusesSweepsOfOtherAmplitudes) {
  SubjectSweep a, b;
  a.points.resize(2);
  b.points.resize(2);
  a.points[0].amplitude_deg = b.points[0].amplitude_deg = 6;
  a.points[1].amplitude_deg = 8;
  b.points[1].amplitude_deg = 11;
  EXPECT_THROW(CompareWithModel(a, b, {}, {}), std::invalid_argument);
  b.points.pop_back();
  EXPECT_THROW(CompareWithModel(a, b, {}, {}), std::invalid_argument);
}

}  // namespace
