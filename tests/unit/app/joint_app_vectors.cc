// The application state machine against a scripted I/O (no plant): transitions,
// refusals, the same-tick fault stop, and the event stream. Runs on the host and on
// the Cortex-M4.
#include <cmath>
#include <cstdint>
#include <numbers>

#include "mjc/app/joint_app.h"
#include "vector_test.h"

namespace {

using namespace mjc;
using namespace mjc::app;

// Sensors at rest at zero; corrupts the joint frame on request; records actuation.
struct ScriptedIo {
  bool corrupt = false;
  Actuation written;
  int writes = 0;
  Sample ISR_Read() {
    Sample s;
    s.joint_frame = EncodeJointFrame(0, false);
    if (corrupt) s.joint_frame ^= 0x0001u;
    return s;
  }
  void ISR_Write(const Actuation& a) {
    written = a;
    ++writes;
  }
};
static_assert(hal::JointIo<ScriptedIo>);

mjc::Calibration TestCalibration() {
  mjc::Calibration c;
  c.backlash.c_right = Angle::FromDouble(0.0175);
  c.backlash.c_left = Angle::FromDouble(-0.0175);
  return c;
}

SineConfig ShortSine() {
  SineConfig s;
  s.amplitude = Angle::FromDouble(0.1);
  s.frequency = Frequency::FromDouble(10.0);
  s.repetitions = 2;
  return s;
}

// Each case has its own static app: a JointApp holds its delay lines and queues
// (~20 KB), too much for a test's stack on the target.
#define MJC_FRESH_APP(name) static JointApp name(ControlConfig{})

MJC_VECTOR_TEST(JointApp, TrialRefusedUntilCalibrated) {
  MJC_FRESH_APP(app);
  ScriptedIo io;
  VT_EXPECT_TRUE(app.StartTrial(ShortSine()).result ==
                 CommandOutcomeCode::kRefusedUncalibrated);
  VT_EXPECT_TRUE(app.SetCalibration(TestCalibration()).result ==
                 CommandOutcomeCode::kAccepted);
  app.ISR_Tick(io);
  VT_EXPECT_TRUE(app.calibrated());
  VT_EXPECT_TRUE(app.StartTrial(ShortSine()).result == CommandOutcomeCode::kAccepted);
  app.ISR_Tick(io);
  VT_EXPECT_TRUE(app.state() == BoardState::kRunning);
  VT_EXPECT_TRUE(io.written.bridge_enabled);
}

MJC_VECTOR_TEST(JointApp, InvalidCalibrationRefusedWithReasonOldKept) {
  MJC_FRESH_APP(app);
  ScriptedIo io;
  app.SetCalibration(TestCalibration());
  app.ISR_Tick(io);
  mjc::Calibration bad = TestCalibration();
  bad.backlash.c_left = Angle::FromDouble(0.1);  // left above right
  CommandOutcome o = app.SetCalibration(bad);
  VT_EXPECT_TRUE(o.result == CommandOutcomeCode::kRefusedInvalid);
  VT_EXPECT_EQ(o.detail, static_cast<int>(BacklashConfigError::kLeftAboveRight));
  bad = TestCalibration();
  bad.sea_stiffness = Stiffness{};
  o = app.SetCalibration(bad);
  VT_EXPECT_TRUE(o.result == CommandOutcomeCode::kRefusedInvalid);
  VT_EXPECT_EQ(o.detail, static_cast<int>(CalibrationError::kStiffness));
  bad = TestCalibration();
  bad.joint_zero_count = kJointCountsPerRev;
  o = app.SetCalibration(bad);
  VT_EXPECT_TRUE(o.result == CommandOutcomeCode::kRefusedInvalid);
  VT_EXPECT_EQ(o.detail, static_cast<int>(CalibrationError::kJointZero));
  app.ISR_Tick(io);
  VT_EXPECT_TRUE(app.control().config().backlash.c_left ==
                 TestCalibration().backlash.c_left);
}

MJC_VECTOR_TEST(JointApp, TrialRunsToCompletionThenIdles) {
  MJC_FRESH_APP(app);
  ScriptedIo io;
  app.SetCalibration(TestCalibration());
  app.ISR_Tick(io);
  app.StartTrial(ShortSine());
  int running_ticks = 0;
  for (int i = 0; i < 5000 && (i == 0 || app.state() != BoardState::kIdle); ++i) {
    app.ISR_Tick(io);
    if (app.state() == BoardState::kRunning) ++running_ticks;
  }
  VT_EXPECT_TRUE(app.state() == BoardState::kIdle);
  VT_EXPECT_TRUE(!io.written.bridge_enabled);
  VT_EXPECT_EQ(running_ticks, 2 * 1000);  // two 10 Hz cycles at 10 kHz
  // Events: running, then idle.
  AppEvent e;
  int changes = 0;
  while (app.PopEvent(&e)) {
    if (e.kind == AppEvent::Kind::kStateChanged) ++changes;
  }
  VT_EXPECT_EQ(changes, 2);
}

MJC_VECTOR_TEST(JointApp, EachWindowsFitSumsFollowItsEvent) {
  // The main loop takes each kWindow event's sums by its start tick: every window of
  // the trial finds its own (as many samples as the window has ticks), and a start
  // tick no window had finds none.
  MJC_FRESH_APP(app);
  ScriptedIo io;
  app.SetCalibration(TestCalibration());
  app.ISR_Tick(io);
  app.StartTrial(ShortSine());
  int windows = 0, matched = 0;
  AppEvent e;
  // Past the trial's end: the last window closes a velocity delay after it.
  for (int i = 0; i < 5000; ++i) {
    app.ISR_Tick(io);
    while (app.PopEvent(&e)) {
      if (e.kind != AppEvent::Kind::kWindow) continue;
      ++windows;
      InterfaceFitSums sums;
      if (app.PopWindowFit(e.window.start_tick, &sums) &&
          sums.count == e.window.end_tick - e.window.start_tick) {
        ++matched;
      }
    }
  }
  VT_EXPECT_EQ(windows, 4);  // flexion and extension of two cycles
  VT_EXPECT_EQ(matched, 4);
  InterfaceFitSums none;
  VT_EXPECT_TRUE(!app.PopWindowFit(12345, &none));
  VT_EXPECT_EQ(app.dropped_window_fits(), 0u);
}

// The joint swinging ±0.2 rad at 2 Hz (2.5 rad/s at most, inside the velocity limit)
// against a motor at rest: the fit of each window (2,500 ticks of a 2 Hz motion) comes
// out valid (τ = K(θ̃ − θ_j) against a moving θ_j).
struct SwingingIo {
  int tick = 0;
  Sample ISR_Read() {
    const double angle = 0.2 * std::sin(2 * std::numbers::pi * 2.0 * tick++ / 10000.0);
    const long count = std::lround(angle * kJointCountsPerRev / (2 * std::numbers::pi));
    Sample s;
    s.joint_frame = EncodeJointFrame(static_cast<std::uint16_t>(count & 0x3FFF), false);
    return s;
  }
  void ISR_Write(const Actuation&) {}
};
static_assert(hal::JointIo<SwingingIo>);

// Runs `ticks` ticks, solving each window's fit in the main loop as the CAN node does;
// the number of valid fits.
int RunSolvingFits(JointApp& app, SwingingIo& io, int ticks) {
  int valid = 0;
  for (int i = 0; i < ticks; ++i) {
    app.ISR_Tick(io);
    AppEvent e;
    while (app.PopEvent(&e)) {
      if (e.kind == AppEvent::Kind::kWindow &&
          app.SolveWindowFit(e.window.start_tick).valid()) {
        ++valid;
      }
    }
  }
  return valid;
}

MJC_VECTOR_TEST(JointApp, ATrialsFitsReplaceTheAttachmentPriorASweepsDoNot) {
  // A calibration sweep moves the robot without the hand: its fits describe no
  // attachment and leave the velocity model's prior. A trial's valid fit replaces it
  // from the next tick, clamped to k, b ≥ 0.
  MJC_FRESH_APP(app);
  SwingingIo io;
  app.SetCalibration(TestCalibration());
  app.ISR_Tick(io);
  const AttachmentParams prior = ControlConfig{}.attachment_prior;
  RampedSineConfig sweep;
  sweep.end_amplitude = Angle::FromDouble(0.1);
  sweep.frequency = Frequency::FromDouble(2.0);
  sweep.repetitions = 1;
  VT_EXPECT_TRUE(app.StartCalibrationSweep(sweep).result ==
                 CommandOutcomeCode::kAccepted);
  VT_EXPECT_TRUE(RunSolvingFits(app, io, 6000) > 0);
  VT_EXPECT_TRUE(app.state() == BoardState::kIdle);
  VT_EXPECT_TRUE(app.control().attachment() == prior);

  SineConfig trial;
  trial.amplitude = Angle::FromDouble(0.1);
  trial.frequency = Frequency::FromDouble(2.0);
  trial.repetitions = 1;
  VT_EXPECT_TRUE(app.StartTrial(trial).result == CommandOutcomeCode::kAccepted);
  VT_EXPECT_TRUE(RunSolvingFits(app, io, 6000) > 0);
  // The last fit: the joint against the spring alone reads as k = −K, clamped to 0.
  VT_EXPECT_TRUE(app.control().attachment().stiffness == Stiffness{});
  VT_EXPECT_TRUE(!(app.control().attachment().damping == prior.damping));
  VT_EXPECT_EQ(app.dropped_attachment_updates(), 0u);
}

MJC_VECTOR_TEST(JointApp, FaultStopsBridgeInSameTickAndLatches) {
  MJC_FRESH_APP(app);
  ScriptedIo io;
  app.SetCalibration(TestCalibration());
  app.ISR_Tick(io);
  app.StartTrial(ShortSine());
  for (int i = 0; i < 100; ++i) app.ISR_Tick(io);
  VT_EXPECT_TRUE(io.written.bridge_enabled);
  io.corrupt = true;
  app.ISR_Tick(io);
  VT_EXPECT_TRUE(!io.written.bridge_enabled);
  VT_EXPECT_EQ(io.written.duty.raw(), 0);
  VT_EXPECT_TRUE(app.state() == BoardState::kFault);
  // Refused while the cause is present; accepted when it is gone.
  app.ClearFaults();
  app.ISR_Tick(io);
  VT_EXPECT_TRUE(app.state() == BoardState::kFault);
  VT_EXPECT_TRUE(app.StartTrial(ShortSine()).result ==
                 CommandOutcomeCode::kRefusedNotIdle);
  io.corrupt = false;
  app.ISR_Tick(io);
  app.ClearFaults();
  app.ISR_Tick(io);
  VT_EXPECT_TRUE(app.state() == BoardState::kIdle);
  bool saw_fault = false, saw_refusal = false;
  AppEvent e;
  while (app.PopEvent(&e)) {
    if (e.kind == AppEvent::Kind::kFault && e.fault == Fault::kJointParity)
      saw_fault = true;
    if (e.kind == AppEvent::Kind::kCommandDone &&
        e.outcome.result == CommandOutcomeCode::kRefusedFaultActive) {
      saw_refusal = true;
    }
  }
  VT_EXPECT_TRUE(saw_fault && saw_refusal);
}

MJC_VECTOR_TEST(JointApp, ConfigurationRefusedUnlessIdle) {
  MJC_FRESH_APP(app);
  ScriptedIo io;
  app.SetCalibration(TestCalibration());
  app.ISR_Tick(io);
  app.StartTrial(ShortSine());
  app.ISR_Tick(io);
  VT_EXPECT_TRUE(app.Configure(ControlConfig{}).result ==
                 CommandOutcomeCode::kRefusedNotIdle);
  VT_EXPECT_TRUE(app.SetCalibration(TestCalibration()).result ==
                 CommandOutcomeCode::kRefusedNotIdle);
  app.Stop();
  app.ISR_Tick(io);
  VT_EXPECT_TRUE(app.state() == BoardState::kIdle);
  VT_EXPECT_TRUE(app.Configure(ControlConfig{}).result == CommandOutcomeCode::kAccepted);
}

MJC_VECTOR_TEST(JointApp, LatestIsWhatTheLastTickLeft) {
  MJC_FRESH_APP(app);
  ScriptedIo io;
  const auto same = [&] {
    const JointApp::Snapshot s = app.Latest();
    const TickResult& r = app.last();
    return s.telemetry.tick == r.telemetry.tick &&
           s.telemetry.energy_sum == r.telemetry.energy_sum &&
           s.telemetry.setpoint == r.telemetry.setpoint &&
           s.telemetry.fault == r.telemetry.fault &&
           s.bridge_enabled == io.written.bridge_enabled && s.state == app.state() &&
           s.calibrated == app.calibrated();
  };
  VT_EXPECT_TRUE(same());  // before any tick: the defaults
  app.SetCalibration(TestCalibration());
  app.ISR_Tick(io);
  VT_EXPECT_TRUE(same() && app.Latest().calibrated);
  app.StartTrial(ShortSine());
  for (int i = 0; i < 50; ++i) {
    app.ISR_Tick(io);
    VT_EXPECT_TRUE(same());
  }
  VT_EXPECT_TRUE(app.Latest().bridge_enabled &&
                 app.Latest().state == BoardState::kRunning);
  VT_EXPECT_EQ(app.Latest().telemetry.tick, 50u);  // the 51st tick: they count from 0
  io.corrupt = true;
  app.ISR_Tick(io);
  VT_EXPECT_TRUE(same());
  VT_EXPECT_TRUE(app.Latest().state == BoardState::kFault &&
                 !app.Latest().bridge_enabled);
  VT_EXPECT_TRUE(app.Latest().telemetry.fault == Fault::kJointParity);
}

}  // namespace
