// The joint service without any transport: the application's tick on the simulated
// plant, the service's requests made and its reports read directly, no CAN node built.
// The attachment model of the velocity estimator must adapt from the service's window
// fits alone, to the plant's own attachment (ground truth), as the board on the bus does
// (SimTrial.TheVelocityModelTakesTheBoardsOwnFitOfTheAttachment).
#include "mjc/service/joint_service.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <vector>

#include "hal/sim/sim_flash.h"
#include "hal/sim/sim_joint_io.h"
#include "mjc/app/joint_app.h"
#include "mjc/app/joint_config.h"
#include "mjc/plant/params.h"
#include "mjc/plant/plant.h"
#include "mjc/protocol/codec.h"

namespace {

using namespace mjc;
using service::Report;

// Every report the service emits, in order.
class Reports final : public service::ReportSink {
 public:
  std::vector<Report> all;

 private:
  void DoTake(const Report& r) override { all.push_back(r); }
};

// The tick on the plant and the main loop's pass, nothing else: no JointBoard, no node.
struct Rig {
  Rig(const plant::PlantParams& params, const ControlConfig& config,
      app::CalibrationStore* store = nullptr)
      : period_s(1.0 / config.tick_hz),
        plant(std::make_unique<plant::Plant>(params)),
        io(std::make_unique<hal::SimJointIo>(plant.get())),
        app(std::make_unique<app::JointApp>(config)),
        service(app.get(), store) {
    service.Attach(&reports);
  }
  void Run(int ticks) {
    for (int i = 0; i < ticks; ++i) {
      app->ISR_Tick(*io);
      plant->Step(io->duty(), io->bridge_enabled(), period_s);
      service.Poll();
    }
  }
  // The index of the first report of `kind` from `from` on, or -1.
  long Find(Report::Kind kind, std::size_t from = 0) const {
    for (std::size_t i = from; i < reports.all.size(); ++i) {
      if (reports.all[i].kind == kind) return static_cast<long>(i);
    }
    return -1;
  }
  double period_s;
  std::unique_ptr<plant::Plant> plant;
  std::unique_ptr<hal::SimJointIo> io;
  std::unique_ptr<app::JointApp> app;  // ~20 KB: on the heap, as SimBoard keeps its board
  service::JointService service;
  Reports reports;
};

TEST(JointService, TheAttachmentModelAdaptsWithNoTransport) {
  // A prior a third of subject 2's attachment (k 1.8, b 0.1 against 5.5, 0.29).
  ControlConfig config = app::DefaultJointConfig();
  const AttachmentParams prior{Stiffness::Quantize(1.8), Damping::Quantize(0.1)};
  config.attachment_prior = prior;
  plant::PlantParams params = plant::LoadPlantParams("default");
  params.integration.max_step_s = 100e-6;
  const plant::InterfaceParams subject = plant::LoadPlantParams("subject2").interface;
  params.interface = subject;
  Rig rig(params, config);
  rig.Run(1);  // the first tick seeds the signal chain

  // The calibration the plant was built with (its cable's slack), uploaded as a record.
  protocol::CalibrationRecord record;
  record.backlash.c_right = Angle::Quantize(params.cable.c_right_rad);
  record.backlash.c_left = Angle::Quantize(params.cable.c_left_rad);
  record.sea_stiffness = Calibration{}.sea_stiffness;
  rig.service.Upload(record);
  rig.Run(2);
  const long calibrated = rig.Find(Report::Kind::kCalibrationDone);
  ASSERT_GE(calibrated, 0);
  EXPECT_EQ(rig.reports.all[static_cast<std::size_t>(calibrated)].calibration,
            protocol::CalibrationResult::kAccepted);
  ASSERT_TRUE(rig.app->calibrated());
  EXPECT_EQ(rig.app->control().attachment().stiffness, prior.stiffness);

  // The paper's trial at 11°: five cycles at 0.5 Hz between 1.5 s rests.
  protocol::TrialConfig trial;
  trial.amplitude = Angle::Quantize(11.0 * 3.14159265358979323846 / 180.0);
  trial.frequency_mHz = 500;
  trial.repetitions = 5;
  trial.rest_100ms = 15;
  rig.service.SetTrialConfig(trial);
  const std::size_t before = rig.reports.all.size();
  rig.service.Submit(
      {protocol::CommandCode::kStartTrial, 1, 0, protocol::ConfigDigestOf(trial)});
  rig.Run(2);
  const long started = rig.Find(Report::Kind::kMotionStarted, before);
  ASSERT_GE(started, 0) << "the trial did not start";
  // Until the board is idle again (13 s of trial; 15 s at most).
  for (int s = 0; s < 15 && rig.app->state() != app::BoardState::kIdle; ++s) {
    rig.Run(static_cast<int>(config.tick_hz));
  }
  ASSERT_EQ(rig.app->state(), app::BoardState::kIdle);
  EXPECT_EQ(rig.Find(Report::Kind::kFault, before), -1);

  // The windows' fits came as reports; the last valid one is the model the tick holds.
  int windows = 0;
  const InterfaceFit* last_valid = nullptr;
  for (const Report& r : rig.reports.all) {
    if (r.kind != Report::Kind::kWindow) continue;
    ++windows;
    if (r.fit.valid()) last_valid = &r.fit;
  }
  EXPECT_EQ(windows, 10);  // a flexion and an extension a cycle
  ASSERT_NE(last_valid, nullptr);
  const AttachmentParams& model = rig.app->control().attachment();
  EXPECT_EQ(model.stiffness, std::max(last_valid->stiffness, Stiffness{}));
  EXPECT_EQ(model.damping, std::max(last_valid->damping, Damping{}));
  // Against the plant's attachment: as close as the board on the bus gets.
  EXPECT_NEAR(model.stiffness.ToDouble(), subject.stiffness_Nm_per_rad,
              0.03 * subject.stiffness_Nm_per_rad);
  EXPECT_NEAR(model.damping.ToDouble(), subject.damping_Nm_s_per_rad,
              0.03 * subject.damping_Nm_s_per_rad);
  std::printf("[ model    ] tick %u: fitted k %.3f b %.4f (plant: %.3f, %.4f)\n",
              rig.service.last().telemetry.tick, model.stiffness.ToDouble(),
              model.damping.ToDouble(), subject.stiffness_Nm_per_rad,
              subject.damping_Nm_s_per_rad);
}

// The service keeps a calibration only once the tick applied it, keeps none the tick
// refused, and hands the kept one to a board that starts again.
TEST(JointService, SavesWhatTheTickAppliedAndRestoresItAtBoot) {
  hal::SimFlash flash(8);
  app::CalibrationStore store(&flash, 3, 7);
  const plant::PlantParams params = plant::LoadPlantParams("default");
  const ControlConfig config = app::DefaultJointConfig();
  protocol::CalibrationRecord record;
  record.backlash.c_right = Angle::Quantize(0.021);
  record.backlash.c_left = Angle::Quantize(-0.013);
  record.sea_stiffness = Stiffness::Quantize(0.6);
  record.joint_zero_count = 1234;
  {
    Rig rig(params, config, &store);
    EXPECT_FALSE(rig.service.Boot().has_value());  // an empty flash: uncalibrated
    rig.Run(1);
    rig.service.Upload(record);
    EXPECT_FALSE(store.Load().has_value()) << "saved before the tick applied it";
    rig.Run(2);
    ASSERT_EQ(rig.Find(Report::Kind::kCalibrationDone), 0);
    EXPECT_EQ(rig.reports.all[0].calibration, protocol::CalibrationResult::kAccepted);
    const auto saved = store.Load();
    ASSERT_TRUE(saved.has_value());
    EXPECT_EQ(saved->record.backlash.c_right, record.backlash.c_right);
    EXPECT_EQ(saved->record.backlash.c_left, record.backlash.c_left);
    EXPECT_EQ(saved->record.sea_stiffness, record.sea_stiffness);
    EXPECT_EQ(saved->record.joint_zero_count, record.joint_zero_count);

    // A joint zero beyond the encoder's counts: refused, and the store keeps the first.
    protocol::CalibrationRecord bad = record;
    bad.joint_zero_count = 0xFFFF;
    rig.service.Upload(bad);
    rig.Run(2);
    ASSERT_EQ(rig.reports.all.size(), 2u);
    EXPECT_EQ(rig.reports.all[1].calibration, protocol::CalibrationResult::kOutOfRange);
    EXPECT_EQ(store.Load()->sequence, saved->sequence);
  }
  // A board that starts again from the same flash is calibrated at its first tick.
  Rig rig(params, config, &store);
  const auto restored = rig.service.Boot();
  ASSERT_TRUE(restored.has_value());
  rig.Run(1);
  EXPECT_TRUE(rig.app->calibrated());
  EXPECT_EQ(rig.app->config().backlash.c_right, record.backlash.c_right);
  EXPECT_EQ(rig.app->config().backlash.c_left, record.backlash.c_left);
  EXPECT_EQ(rig.app->config().sea_stiffness, record.sea_stiffness);
  EXPECT_EQ(rig.app->config().joint_encoder.zero_offset, record.joint_zero_count);
}

}  // namespace
