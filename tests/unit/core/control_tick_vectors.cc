// ControlTick end to end: sensor words in, windows and actuation out, against a small
// double-precision plant written here: an ideal motor that follows the setpoint, a
// Bowden cable with slack (a play operator with the true c_r, c_l), the SEA spring K,
// and a massless joint on a Kelvin–Voigt interface to ground,
//   b·θ̇ = K(θ̃ − θ) − k·θ   (solved exactly per tick for a piecewise-constant θ̃).
// Ground-truth interface power is τ·θ̇ from the plant's own θ; window energies are
// summed over the tick ranges the board reports (already aligned to the instant).
#include <cmath>
#include <cstdint>
#include <numbers>

#include "mjc/core/control_tick.h"
#include "vector_test.h"

namespace {

using namespace mjc;

constexpr double kCountsPerRad = 2048.0 * 100 / (2 * std::numbers::pi);

struct MiniPlant {
  double k_sea, k_if, b_if, c_r, c_l;
  double cable = 0, theta = 0;
  // Advances one tick with the motor at `motor` (rad); returns the interface torque.
  void Step(double motor, double dt) {
    const double lo = motor - c_r, hi = motor - c_l;
    cable = cable < lo ? lo : (cable > hi ? hi : cable);
    const double steady = k_sea * cable / (k_sea + k_if);
    if (b_if == 0) {
      theta = steady;
    } else {
      theta = steady + (theta - steady) * std::exp(-dt * (k_sea + k_if) / b_if);
    }
  }
  double torque() const { return k_sea * (cable - theta); }
  Sample Read(double motor) const {
    Sample s;
    s.motor_count =
        static_cast<std::uint16_t>(std::llround(motor * kCountsPerRad) & 0xFFFF);
    const auto count = static_cast<std::uint16_t>(
        static_cast<std::int32_t>(std::lround(theta / (2 * std::numbers::pi) * 16384)) &
        0x3FFF);
    s.joint_frame = EncodeJointFrame(count, false);
    return s;
  }
};

TickResult StepOf(ControlTick& tick, const Sample& sample) {
  TickResult r;
  tick.ISR_Step(sample, &r);
  return r;
}

ControlConfig PaperConfig() {
  ControlConfig c;
  c.backlash.c_right = Angle::Quantize(1.0 * std::numbers::pi / 180);
  c.backlash.c_left = Angle::Quantize(-1.0 * std::numbers::pi / 180);
  c.sea_stiffness = Stiffness::Quantize(0.63);
  return c;
}

struct TrialResult {
  int flexion_windows = 0;
  double worst_energy_err = 0;  // relative, over loading and unloading halves
  double worst_eta_err = 0;     // points
  double mean_eta = 0;
  bool started = false;
  int disabled_ticks = 0;  // after arming: the bridge must stay on for a healthy trial
};

// A five-repetition 25° sine trial at 0.5 Hz.
TrialResult RunTrial(double k_if, double b_if) {
  static ControlTick tick;  // 8 KB of delay storage: static, as on the target
  const ControlConfig config = PaperConfig();
  tick.Configure(config);
  MiniPlant plant{0.63, k_if, b_if, config.backlash.c_right.ToDouble(),
                  config.backlash.c_left.ToDouble()};
  SineConfig sine;
  sine.amplitude = Angle::Quantize(25.0 * std::numbers::pi / 180);
  sine.frequency = Frequency::Quantize(0.5);
  sine.repetitions = 5;
  sine.rest_ms = 500;
  static double truth_power[120000];
  double motor = 0, last_theta = 0;
  TrialResult res;
  double eta_sum = 0;
  const int ticks = 5 * 20000 + 2 * 5000 + 1000;
  // The tick's counter goes on from an earlier trial on the same (static) tick: truth
  // is indexed from this trial's first tick.
  std::uint32_t first = 0;
  for (int i = 0; i < ticks; ++i) {
    if (i == 10) {
      tick.Arm(true);
      res.started = tick.trajectory().StartSine(sine) == TrajectoryError::kOk;
    }
    plant.Step(motor, 1e-4);
    // Ground truth at tick i: τ·θ̇ with a central difference done one tick late below.
    const TickResult r = StepOf(tick, plant.Read(motor));
    if (i == 0) first = r.telemetry.tick;
    truth_power[i] = 0;
    if (i > 0) truth_power[i - 1] = plant.torque() * (plant.theta - last_theta) / 1e-4;
    last_theta = plant.theta;
    motor = r.telemetry.setpoint.ToDouble();  // the ideal motor reaches it next tick
    if (i >= 10 && !r.actuation.bridge_enabled) ++res.disabled_ticks;
    if (r.window_completed && r.window.motion == Motion::kFlexion) {
      const WindowSummary& w = r.window;
      double load = 0, unload = 0;
      for (std::uint32_t t = w.start_tick; t < w.peak_tick; ++t)
        load += truth_power[t - first] * 1e-4;
      for (std::uint32_t t = w.peak_tick; t < w.end_tick; ++t)
        unload += truth_power[t - first] * 1e-4;
      const double e1 = std::fabs(w.loading.ToDouble() - load) / std::fabs(load);
      const double e2 = std::fabs(w.unloading.ToDouble() - unload) / std::fabs(load);
      const double eta = (1 - std::fabs(unload) / load) * 100;
      res.worst_energy_err = std::fmax(res.worst_energy_err, std::fmax(e1, e2));
      res.worst_eta_err =
          std::fmax(res.worst_eta_err, std::fabs(w.eta_percent.ToDouble() - eta));
      eta_sum += w.eta_percent.ToDouble();
      ++res.flexion_windows;
    }
  }
  res.mean_eta = res.flexion_windows ? eta_sum / res.flexion_windows : 0;
  return res;
}

MJC_VECTOR_TEST(ControlTick, LossyTrialMatchesPlantTruth) {
  const TrialResult r = RunTrial(3.1, 0.4);
  VT_EXPECT_TRUE(r.started);
  VT_EXPECT_EQ(r.disabled_ticks, 0);
  VT_EXPECT_EQ(r.flexion_windows, 5);
  VT_EXPECT_LE(r.worst_energy_err, 0.02);  // 2 % of the loading energy
  VT_EXPECT_LE(r.worst_eta_err, 1.0);      // 1 point
  VT_EXPECT_TRUE(r.mean_eta > 5.0);        // a lossy interface reads as lossy
}

MJC_VECTOR_TEST(ControlTick, ElasticTrialReadsNoLossThroughBacklash) {
  const TrialResult r = RunTrial(3.1, 0.0);
  VT_EXPECT_EQ(r.disabled_ticks, 0);
  VT_EXPECT_EQ(r.flexion_windows, 5);
  VT_EXPECT_LE(std::fabs(r.mean_eta), 1.0);
}

MJC_VECTOR_TEST(ControlTick, CorruptFrameDisablesBridgeInSameTick) {
  static ControlTick tick;
  tick.Configure(PaperConfig());
  tick.Arm(true);
  tick.trajectory().Hold(Angle{});
  Sample good;
  good.joint_frame = EncodeJointFrame(0, false);
  for (int i = 0; i < 100; ++i)
    VT_EXPECT_TRUE(StepOf(tick, good).actuation.bridge_enabled);
  Sample bad = good;
  bad.joint_frame =
      static_cast<std::uint16_t>(good.joint_frame ^ 0x0004u);  // one bit flipped
  const TickResult r = StepOf(tick, bad);
  VT_EXPECT_TRUE(r.raised == Fault::kJointParity);
  VT_EXPECT_TRUE(!r.actuation.bridge_enabled);
  VT_EXPECT_EQ(r.actuation.duty.raw(), 0);
  // Latched on healthy samples, until cleared; the clear works once the cause is gone.
  const TickResult later = StepOf(tick, good);
  VT_EXPECT_TRUE(!later.actuation.bridge_enabled);
  VT_EXPECT_TRUE(later.telemetry.fault == Fault::kJointParity);
  VT_EXPECT_TRUE(later.raised == Fault::kNone);
  tick.RequestClearFaults();
  const TickResult cleared = StepOf(tick, good);
  VT_EXPECT_TRUE(cleared.clear == FaultClear::kCleared);
  VT_EXPECT_TRUE(cleared.actuation.bridge_enabled);
}

MJC_VECTOR_TEST(ControlTick, TickOverrunAndTimeoutStopTheMotor) {
  static ControlTick tick;
  tick.Configure(PaperConfig());
  tick.Arm(true);
  Sample s;
  s.joint_frame = EncodeJointFrame(0, false);
  StepOf(tick, s);
  s.tick_overrun = true;
  TickResult r = StepOf(tick, s);
  VT_EXPECT_TRUE(r.raised == Fault::kTickOverrun && !r.actuation.bridge_enabled);
  tick.RequestClearFaults();  // the cause is still in this tick's sample: refused
  r = StepOf(tick, s);
  VT_EXPECT_TRUE(r.clear == FaultClear::kRefused && !r.actuation.bridge_enabled);
  s.tick_overrun = false;
  tick.RequestClearFaults();  // gone in this tick's sample: cleared in the same tick
  r = StepOf(tick, s);
  VT_EXPECT_TRUE(r.clear == FaultClear::kCleared && r.actuation.bridge_enabled);
  // Faults raised outside the tick: latched by the very next tick; events, not
  // conditions: the following tick's clear succeeds, nothing is left over.
  for (const Fault f :
       {Fault::kCommandTimeout, Fault::kHostHeartbeatLost, Fault::kCanBusOff}) {
    tick.RaiseExternalFault(f);
    r = StepOf(tick, s);
    VT_EXPECT_TRUE(r.raised == f && !r.actuation.bridge_enabled);
    tick.RequestClearFaults();
    r = StepOf(tick, s);
    VT_EXPECT_TRUE(r.clear == FaultClear::kCleared && r.actuation.bridge_enabled);
  }
  // Only those: a sensor or limit code raised from outside is ignored.
  tick.RaiseExternalFault(Fault::kTorqueLimit);
  r = StepOf(tick, s);
  VT_EXPECT_TRUE(r.raised == Fault::kNone && r.actuation.bridge_enabled);
}

MJC_VECTOR_TEST(ControlTick, RefusedConfigKeepsTheOldOne) {
  static ControlTick tick;
  ControlConfig c = PaperConfig();
  VT_EXPECT_TRUE(tick.Configure(c) == ControlConfigError::kOk);
  ControlConfig bad = c;
  bad.backlash.c_left = Angle::Quantize(0.1);  // left above right
  VT_EXPECT_TRUE(tick.Configure(bad) == ControlConfigError::kBacklash);
  bad = c;
  bad.velocity_window = 500;  // even
  VT_EXPECT_TRUE(tick.Configure(bad) == ControlConfigError::kVelocityWindow);
  bad = c;
  bad.sea_stiffness = Stiffness{};
  VT_EXPECT_TRUE(tick.Configure(bad) == ControlConfigError::kStiffness);
  bad = c;
  bad.supervisor.torque_max = Torque::FromDouble(-1.0);  // would fault every tick
  VT_EXPECT_TRUE(tick.Configure(bad) == ControlConfigError::kSupervisor);
  VT_EXPECT_TRUE(tick.config().backlash.c_left == c.backlash.c_left);
  VT_EXPECT_EQ(tick.delay_ticks(), c.velocity_window / 2);
}

MJC_VECTOR_TEST(ControlTick, AFittedAttachmentOutlivesAConfigureThatKeepsThePrior) {
  // The velocity model's attachment: the config's prior, then a fit; a Configure that
  // changes something else (a calibration, a gain) keeps the fit, one with a new prior
  // takes that prior; a negative fit is refused and changes nothing.
  static ControlTick tick;
  ControlConfig c = PaperConfig();
  VT_EXPECT_TRUE(tick.Configure(c) == ControlConfigError::kOk);
  VT_EXPECT_TRUE(tick.attachment() == c.attachment_prior);
  const AttachmentParams fit{Stiffness::FromDouble(5.5), Damping::FromDouble(0.29)};
  VT_EXPECT_TRUE(tick.SetAttachment(fit));
  VT_EXPECT_TRUE(!tick.SetAttachment({Stiffness::FromDouble(-1.0), Damping{}}));
  VT_EXPECT_TRUE(tick.attachment() == fit);
  c.sea_stiffness = Stiffness::FromDouble(0.7);
  VT_EXPECT_TRUE(tick.Configure(c) == ControlConfigError::kOk);
  VT_EXPECT_TRUE(tick.attachment() == fit);
  c.attachment_prior = {Stiffness::FromDouble(3.0), Damping::FromDouble(0.2)};
  VT_EXPECT_TRUE(tick.Configure(c) == ControlConfigError::kOk);
  VT_EXPECT_TRUE(tick.attachment() == c.attachment_prior);
  c.attachment_prior.damping = Damping::FromDouble(-0.1);
  VT_EXPECT_TRUE(tick.Configure(c) == ControlConfigError::kAttachmentPrior);
}

MJC_VECTOR_TEST(ControlTick, ReconfiguringKeepsTheMotorAngle) {
  // The pulley rests at −0.1 rad (the timer's unsigned count just below 65,536) when a
  // calibration or parameter write reconfigures the tick: the angle must carry on, not
  // restart from the raw count (+1.9 rad, beyond the motor limit: a false fault).
  static ControlTick tick;
  VT_EXPECT_TRUE(tick.Configure(PaperConfig()) == ControlConfigError::kOk);
  const double rad_per_count = 2 * std::numbers::pi / (2048.0 * 100.0);
  const auto counts = static_cast<std::int32_t>(std::lround(-0.1 / rad_per_count));
  Sample s;
  s.joint_frame = EncodeJointFrame(0, false);
  for (std::int32_t c = 0; c >= counts; c -= 16) {  // 0.5 rad/s
    s.motor_count = static_cast<std::uint16_t>(c & 0xFFFF);
    StepOf(tick, s);
  }
  s.motor_count = static_cast<std::uint16_t>(counts & 0xFFFF);
  const TickResult before = StepOf(tick, s);
  VT_EXPECT_NEAR(before.telemetry.motor.ToDouble(), counts * rad_per_count, 1e-6);
  VT_EXPECT_TRUE(tick.Configure(PaperConfig()) == ControlConfigError::kOk);
  const TickResult after = StepOf(tick, s);
  VT_EXPECT_NEAR(after.telemetry.motor.ToDouble(), counts * rad_per_count, 1e-6);
  VT_EXPECT_TRUE(after.raised == Fault::kNone);
}

}  // namespace
