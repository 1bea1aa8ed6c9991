// The supervisor: every fault code is raised by the Check() whose input carries its
// cause, turns the bridge off in that same call, stays latched on healthy inputs, and is
// cleared only by a sample free of every cause Clear() can see (sensor status, limits,
// timing; jump and stuck history restart from the clearing sample). Each threshold is
// tried exactly at its value (no fault) and one LSB beyond it (fault). A long healthy
// run of a joint driven through a slack cable raises nothing. These vectors run on the
// host and on the Cortex-M4 under QEMU.
//
// Expected values come from the documented thresholds (supervisor.h) and from an
// independent model of the joint: counts, angles and the frozen-count runs are computed
// here, never read back from the supervisor's state.
#include <cstdint>
#include <initializer_list>
#include <numbers>
#include <utility>

#include "mjc/core/encoder.h"
#include "mjc/core/quantities.h"
#include "mjc/core/supervisor.h"
#include "vector_test.h"

namespace {

using mjc::Angle;
using mjc::AngularVelocity;
using mjc::Duty;
using mjc::Fault;
using mjc::JointFrameStatus;
using mjc::Supervisor;
using mjc::SupervisorConfig;
using mjc::SupervisorInput;
using mjc::Torque;

constexpr double kJointCountRad =
    2.0 * std::numbers::pi / 16384.0;  // 14-bit joint encoder
constexpr double kMotorCountRad = 2.0 * std::numbers::pi / 204800.0;  // 2048 edges, 100:1
constexpr double kJointCountsPerRad = 1.0 / kJointCountRad;
constexpr double kMotorCountsPerRad = 1.0 / kMotorCountRad;
// The velocity limit's span as the board sets it (the velocity estimator's delay at the
// default 1001-tick window) and its tick rate: a mean speed v is a travel v·span/rate.
constexpr std::uint16_t kSpanTicks = 500;
constexpr std::uint32_t kTickHz = 10000;
constexpr double kSpanS = static_cast<double>(kSpanTicks) / kTickHz;

std::int64_t RoundToInt(double x) {
  return static_cast<std::int64_t>(x < 0 ? x - 0.5 : x + 0.5);
}

// A good sample of a joint at `joint` rad and a motor pulley at `motor` rad, as the
// encoders report them: both angles on their count grids. The position loop is `error`
// rad off its setpoint (by default behind a moving one). The joint moved at a mean
// `joint_velocity` rad/s over the velocity span.
SupervisorInput Sample(double joint, double motor, double torque = 0.05,
                       double joint_velocity = 0.0, double duty = 0.1,
                       double error = 0.01) {
  SupervisorInput in;
  const std::int64_t k = RoundToInt(joint * kJointCountsPerRad);
  in.joint_count = static_cast<std::uint16_t>(static_cast<std::uint64_t>(k) & 0x3FFFu);
  in.joint = Angle::Quantize(static_cast<double>(k) * kJointCountRad);
  in.motor_count = RoundToInt(motor * kMotorCountsPerRad);
  in.motor = Angle::Quantize(static_cast<double>(in.motor_count) * kMotorCountRad);
  in.torque = Torque::Quantize(torque);
  in.joint_travel = Angle::Quantize(joint_velocity * kSpanS);
  in.applied_duty = Duty::Quantize(duty);
  in.motor_error = Angle::Quantize(error);
  return in;
}

int F(Fault f) { return static_cast<int>(f); }

// A supervisor with its config and state, and the tick counter a control loop keeps.
struct Rig {
  explicit Rig(const SupervisorConfig& c = SupervisorConfig{}) : config(c) {
    supervisor.SetVelocitySpan(kSpanTicks, kTickHz);
  }
  Rig(const Rig&) = delete;
  Rig& operator=(const Rig&) = delete;

  Fault Check(const SupervisorInput& in) { return supervisor.Check(tick++, in); }

  SupervisorConfig config;
  Supervisor::State state;
  Supervisor supervisor{&config, &state};
  std::uint32_t tick = 1000;
};

// Feeds `in` n times; returns how many of those Check() calls did not return kNone.
int Feed(Rig& rig, const SupervisorInput& in, int n) {
  int faults = 0;
  for (int i = 0; i < n; ++i) {
    if (rig.Check(in) != Fault::kNone) ++faults;
  }
  return faults;
}

// The life of one fault whose cause Clear() can see: `healthy` runs clean, `faulty`
// trips `want` in its own Check(), the bridge is off from that call on, the fault stays
// latched through healthy samples and through other causes, Clear(faulty) is refused,
// Clear(healthy) succeeds, and the supervisor runs clean again.
void CheckVisibleCauseLifecycle(mjc::vt::Context& vt_context,
                                const SupervisorInput& healthy,
                                const SupervisorInput& faulty, Fault want) {
  // Setup
  Rig rig;
  VT_EXPECT_EQ(Feed(rig, healthy, 200), 0);
  VT_EXPECT_TRUE(rig.supervisor.bridge_enabled());

  // Exercise: the faulty sample.
  const std::uint32_t fault_tick = rig.tick;
  const Fault got = rig.Check(faulty);
  // Verify: same call, bridge off at once.
  VT_EXPECT_EQ(F(got), F(want));
  VT_EXPECT_TRUE(!rig.supervisor.bridge_enabled());
  VT_EXPECT_EQ(F(rig.supervisor.latched()), F(want));
  VT_EXPECT_EQ(rig.state.fault_tick, fault_tick);

  // Latched through healthy samples and a different cause.
  int not_latched = 0;
  for (int i = 0; i < 100; ++i) {
    if (rig.Check(healthy) != want || rig.supervisor.bridge_enabled()) ++not_latched;
  }
  SupervisorInput other = healthy;
  other.tick_overrun = want != Fault::kTickOverrun;
  other.external = want == Fault::kTickOverrun ? Fault::kCommandTimeout : Fault::kNone;
  if (rig.Check(other) != want) ++not_latched;
  VT_EXPECT_EQ(not_latched, 0);
  VT_EXPECT_EQ(rig.state.fault_tick, fault_tick);

  // Clear is refused while the cause is present...
  VT_EXPECT_TRUE(!rig.supervisor.Clear(faulty));
  VT_EXPECT_EQ(F(rig.supervisor.latched()), F(want));
  VT_EXPECT_TRUE(!rig.supervisor.bridge_enabled());
  // ...and succeeds once it is gone.
  VT_EXPECT_TRUE(rig.supervisor.Clear(healthy));
  VT_EXPECT_TRUE(rig.supervisor.bridge_enabled());
  VT_EXPECT_EQ(F(rig.supervisor.latched()), F(Fault::kNone));
  VT_EXPECT_EQ(Feed(rig, healthy, 200), 0);
  // The cause coming back trips the fault again.
  VT_EXPECT_EQ(F(rig.Check(faulty)), F(want));
}

// A joint resting at 0.3 rad against a little torque, motor pulley 0.32 rad.
SupervisorInput Rest() { return Sample(0.3, 0.32); }

MJC_VECTOR_TEST(Supervisor, ConfigsThatWouldLatchOrHideFaultsAreRefused) {
  using mjc::SupervisorConfig;
  using E = mjc::SupervisorConfigError;
  VT_EXPECT_TRUE(mjc::Validate(SupervisorConfig{}) == E::kOk);
  SupervisorConfig c;
  c.joint_min = c.joint_max;
  VT_EXPECT_TRUE(mjc::Validate(c) == E::kJointRange);
  c = {};
  c.motor_max = Angle::FromDouble(-2.5);
  VT_EXPECT_TRUE(mjc::Validate(c) == E::kMotorRange);
  c = {};
  c.torque_max = mjc::Torque{};
  VT_EXPECT_TRUE(mjc::Validate(c) == E::kTorqueMax);
  c = {};
  c.velocity_max = AngularVelocity::FromDouble(-1.0);
  VT_EXPECT_TRUE(mjc::Validate(c) == E::kVelocityMax);
  c = {};
  c.joint_jump_max = Angle{};
  VT_EXPECT_TRUE(mjc::Validate(c) == E::kJointJumpMax);
  c = {};
  c.stuck_motor_travel = Angle{};
  VT_EXPECT_TRUE(mjc::Validate(c) == E::kStuckTravel);
  c = {};
  c.stuck_duty = Duty{};
  VT_EXPECT_TRUE(mjc::Validate(c) == E::kStuckDuty);
  c = {};
  c.motor_stuck_ticks = 0;
  VT_EXPECT_TRUE(mjc::Validate(c) == E::kMotorStuckTicks);
  c = {};
  c.stuck_hold_error = Angle{};
  VT_EXPECT_TRUE(mjc::Validate(c) == E::kStuckHoldError);
}

MJC_VECTOR_TEST(SupervisorFault, JointParity) {
  SupervisorInput faulty = Rest();
  faulty.joint_status = JointFrameStatus::kParityError;
  faulty.joint_count = 0;  // a bad frame carries no count or angle
  faulty.joint = Angle{};
  CheckVisibleCauseLifecycle(vt_context, Rest(), faulty, Fault::kJointParity);
  VT_EXPECT_EQ(F(Fault::kJointParity), 100);
}

MJC_VECTOR_TEST(SupervisorFault, JointErrorFlag) {
  SupervisorInput faulty = Rest();
  faulty.joint_status = JointFrameStatus::kErrorFlag;
  faulty.joint_count = 0;
  faulty.joint = Angle{};
  CheckVisibleCauseLifecycle(vt_context, Rest(), faulty, Fault::kJointErrorFlag);
  VT_EXPECT_EQ(F(Fault::kJointErrorFlag), 101);
}

MJC_VECTOR_TEST(SupervisorFault, JointAngleLimit) {
  // ±1.6 rad: approach within 3 mrad, then step 6 mrad (+ one count) beyond, which is
  // not a jump.
  CheckVisibleCauseLifecycle(vt_context, Sample(1.597, 1.6), Sample(1.603, 1.61),
                             Fault::kJointAngleLimit);
  CheckVisibleCauseLifecycle(vt_context, Sample(-1.597, -1.6), Sample(-1.603, -1.61),
                             Fault::kJointAngleLimit);
  VT_EXPECT_EQ(F(Fault::kJointAngleLimit), 200);
}

MJC_VECTOR_TEST(SupervisorFault, MotorAngleLimit) {
  // ±2.0 rad of motor pulley.
  CheckVisibleCauseLifecycle(vt_context, Sample(1.5, 1.99), Sample(1.5, 2.01),
                             Fault::kMotorAngleLimit);
  CheckVisibleCauseLifecycle(vt_context, Sample(-1.5, -1.99), Sample(-1.5, -2.01),
                             Fault::kMotorAngleLimit);
  VT_EXPECT_EQ(F(Fault::kMotorAngleLimit), 201);
}

MJC_VECTOR_TEST(SupervisorFault, TorqueLimit) {
  // |τ| <= 1 N·m.
  CheckVisibleCauseLifecycle(vt_context, Sample(0.3, 0.32, 0.9), Sample(0.3, 0.32, 1.1),
                             Fault::kTorqueLimit);
  CheckVisibleCauseLifecycle(vt_context, Sample(0.3, 0.32, -0.9), Sample(0.3, 0.32, -1.1),
                             Fault::kTorqueLimit);
  VT_EXPECT_EQ(F(Fault::kTorqueLimit), 202);
}

MJC_VECTOR_TEST(SupervisorFault, VelocityLimit) {
  // The joint's mean speed over the span, |θ_j(n) − θ_j(n − span)|·rate/span <= 5 rad/s.
  CheckVisibleCauseLifecycle(vt_context, Sample(0.3, 0.32, 0.05, 4.9),
                             Sample(0.3, 0.32, 0.05, 5.1), Fault::kVelocityLimit);
  CheckVisibleCauseLifecycle(vt_context, Sample(0.3, 0.32, 0.05, -4.9),
                             Sample(0.3, 0.32, 0.05, -5.1), Fault::kVelocityLimit);
  VT_EXPECT_EQ(F(Fault::kVelocityLimit), 203);
}

// The travel threshold against the exact rational rule, cross-multiplied so that no
// division is in the reference: a travel t (Angle LSBs) over s ticks at r Hz is beyond
// v (AngularVelocity LSBs) iff t·r > v·2^4·s (Angle has 4 fraction bits more). Spans
// and rates that divide nothing evenly, travels around the threshold, both signs.
MJC_VECTOR_TEST(Supervisor, VelocitySpanThresholdIsTheExactMeanSpeed) {
  struct Case {
    double velocity_max;
    std::uint16_t span;
    std::uint32_t rate;
  };
  const Case cases[] = {{5.0, 500, 10000},   {0.1, 500, 10000}, {3.3, 7, 3000},
                        {0.77, 1023, 20000}, {1.0, 16, 1000},   {2.9, 333, 9999}};
  int wrong = 0, tried = 0;
  for (const Case& k : cases) {
    SupervisorConfig config;
    config.velocity_max = AngularVelocity::Quantize(k.velocity_max);
    Supervisor::State state;
    Supervisor supervisor{&config, &state};
    supervisor.SetVelocitySpan(k.span, k.rate);
    const std::int64_t v = config.velocity_max.raw();
    // The boundary travel in double, then ±3 LSBs around it.
    const auto centre = static_cast<std::int64_t>(static_cast<double>(v) * 16.0 *
                                                  static_cast<double>(k.span) / k.rate);
    for (std::int64_t t = centre - 3; t <= centre + 3; ++t) {
      for (const int sign : {1, -1}) {
        const bool beyond = t * k.rate > v * 16 * static_cast<std::int64_t>(k.span);
        SupervisorInput in = Rest();
        in.joint_travel = Angle::FromRaw(static_cast<std::int32_t>(sign * t));
        Supervisor::State fresh;
        Supervisor judge{&config, &fresh};
        judge.SetVelocitySpan(k.span, k.rate);
        const bool faulted = judge.Check(0, in) == Fault::kVelocityLimit;
        if (faulted != beyond) ++wrong;
        ++tried;
      }
    }
  }
  VT_EXPECT_EQ(tried, 6 * 7 * 2);
  VT_EXPECT_EQ(wrong, 0);
}

// Until its span is set the velocity limit trips on any motion: a supervisor someone
// forgot to give a span stops the motor rather than leaving the limit unchecked.
MJC_VECTOR_TEST(Supervisor, WithoutASpanAnyTravelTripsTheVelocityLimit) {
  SupervisorConfig config;
  Supervisor::State state;
  Supervisor supervisor{&config, &state};
  SupervisorInput in = Rest();
  VT_EXPECT_EQ(F(supervisor.Check(0, in)), F(Fault::kNone));
  in.joint_travel = Angle::Epsilon();
  VT_EXPECT_EQ(F(supervisor.Check(1, in)), F(Fault::kVelocityLimit));
  // So does a span or a rate of zero, which has no mean to take.
  for (const auto& [span, rate] : {std::pair<std::uint16_t, std::uint32_t>{0, 10000},
                                   std::pair<std::uint16_t, std::uint32_t>{500, 0}}) {
    Supervisor::State fresh;
    Supervisor zero{&config, &fresh};
    zero.SetVelocitySpan(span, rate);
    VT_EXPECT_EQ(F(zero.Check(0, in)), F(Fault::kVelocityLimit));
  }
}

MJC_VECTOR_TEST(SupervisorFault, TickOverrun) {
  SupervisorInput faulty = Rest();
  faulty.tick_overrun = true;
  CheckVisibleCauseLifecycle(vt_context, Rest(), faulty, Fault::kTickOverrun);
  VT_EXPECT_EQ(F(Fault::kTickOverrun), 300);
}

// The main loop's faults (command timeout, host heartbeat lost, bus-off).
MJC_VECTOR_TEST(SupervisorFault, External) {
  struct Case {
    Fault fault;
    int code;
  };
  for (const Case c :
       {Case{Fault::kCommandTimeout, 301}, Case{Fault::kHostHeartbeatLost, 302},
        Case{Fault::kCanBusOff, 303}}) {
    SupervisorInput faulty = Rest();
    faulty.external = c.fault;
    CheckVisibleCauseLifecycle(vt_context, Rest(), faulty, c.fault);
    VT_EXPECT_EQ(F(c.fault), c.code);
  }
}

MJC_VECTOR_TEST(SupervisorFault, JointJump) {
  for (const double step : {0.02, -0.02}) {
    // Setup
    Rig rig;
    VT_EXPECT_EQ(Feed(rig, Rest(), 200), 0);
    // Exercise: the joint reads 20 mrad away in one tick (200 rad/s).
    const SupervisorInput jumped = Sample(0.3 + step, 0.32);
    const std::uint32_t fault_tick = rig.tick;
    // Verify
    VT_EXPECT_EQ(F(rig.Check(jumped)), F(Fault::kJointJump));
    VT_EXPECT_TRUE(!rig.supervisor.bridge_enabled());
    VT_EXPECT_EQ(rig.state.fault_tick, fault_tick);
    VT_EXPECT_EQ(Feed(rig, Rest(), 100), 100);  // latched
    VT_EXPECT_TRUE(!rig.supervisor.bridge_enabled());
    // A jump is seen only against history: Clear refuses a sample with a visible cause,
    // accepts the jumped reading itself, and the history restarts from it.
    SupervisorInput bad = jumped;
    bad.joint_status = JointFrameStatus::kParityError;
    VT_EXPECT_TRUE(!rig.supervisor.Clear(bad));
    VT_EXPECT_TRUE(!rig.supervisor.bridge_enabled());
    VT_EXPECT_TRUE(rig.supervisor.Clear(jumped));
    VT_EXPECT_TRUE(rig.supervisor.bridge_enabled());
    VT_EXPECT_EQ(Feed(rig, jumped, 200), 0);
    // Jumping back is a new jump.
    VT_EXPECT_EQ(F(rig.Check(Rest())), F(Fault::kJointJump));
  }
  VT_EXPECT_EQ(F(Fault::kJointJump), 102);
}

// The motor travels from `start` at `rate` rad a tick while the joint count stays frozen
// at its value for `joint`. Returns the index (from 0) of the first sample whose motor
// angle is more than 0.6 rad from the one at the last joint-count change, computed from
// the Angle values the samples carry.
int FirstStuckIndex(double joint, double start, double rate, const Angle& at_change) {
  for (int i = 0;; ++i) {
    const SupervisorInput in = Sample(joint, start + rate * i);
    if (mjc::Abs(in.motor - at_change) > Angle::FromDouble(0.6)) return i;
  }
}

MJC_VECTOR_TEST(SupervisorFault, JointStuck) {
  for (const double rate : {5e-4, -5e-4}) {
    // Setup: the joint count changes once (0.29 → 0.3 rad) with the motor at `m0`;
    // then the motor runs at 5 rad/s while the joint count stays frozen.
    Rig rig;
    const double m0 = rate > 0 ? -1.5 : 1.5;
    VT_EXPECT_EQ(Feed(rig, Sample(0.29, m0), 10), 0);
    const SupervisorInput changed = Sample(0.3, m0);
    VT_EXPECT_EQ(F(rig.Check(changed)), F(Fault::kNone));
    const int first = FirstStuckIndex(0.3, m0, rate, changed.motor);
    VT_EXPECT_TRUE(first > 1000 && first < 1300);  // 0.6 rad at 0.5 mrad a tick
    // Exercise and verify: nothing until index `first`, the fault exactly there.
    int early = 0;
    Fault got = Fault::kNone;
    int i = 1;
    for (; i <= first; ++i) {
      got = rig.Check(Sample(0.3, m0 + rate * i, 0.05, 0.0, 0.5));
      if (i < first && got != Fault::kNone) ++early;
    }
    VT_EXPECT_EQ(early, 0);
    VT_EXPECT_EQ(F(got), F(Fault::kJointStuck));
    VT_EXPECT_TRUE(!rig.supervisor.bridge_enabled());
    VT_EXPECT_EQ(rig.state.fault_tick, rig.tick - 1);
    VT_EXPECT_EQ(Feed(rig, Sample(0.3, m0 + rate * first), 100), 100);  // latched

    // Clear with a visible cause is refused; Clear at the stuck reading succeeds and
    // the stuck history restarts from it: the motor needs another 0.6 rad.
    SupervisorInput bad = Sample(0.3, m0 + rate * (first - 1));
    bad.external = Fault::kCommandTimeout;
    VT_EXPECT_TRUE(!rig.supervisor.Clear(bad));
    const SupervisorInput clearing = Sample(0.3, m0 + rate * (first - 1));
    VT_EXPECT_TRUE(rig.supervisor.Clear(clearing));
    VT_EXPECT_TRUE(rig.supervisor.bridge_enabled());
    const double m1 = m0 + rate * (first - 1);
    const int again = FirstStuckIndex(0.3, m1, rate, clearing.motor);
    early = 0;
    for (i = 1; i <= again; ++i) {
      got = rig.Check(Sample(0.3, m1 + rate * i, 0.05, 0.0, 0.5));
      if (i < again && got != Fault::kNone) ++early;
    }
    VT_EXPECT_EQ(early, 0);
    VT_EXPECT_EQ(F(got), F(Fault::kJointStuck));
  }
  VT_EXPECT_EQ(F(Fault::kJointStuck), 103);
}

// The documented hold tolerance (supervisor.h): 2.5e-4 rad off the setpoint.
constexpr double kStuckHoldErrorRad = 2.5e-4;

// A driven tick (duty at or above stuck_duty, the loop more than the hold tolerance off
// its setpoint) whose motor count equals the previous sample's, counted here.
struct FrozenCounter {
  bool have_previous = false;
  std::int64_t previous = 0;
  std::uint32_t run = 0;
  void Add(const SupervisorInput& in, Duty stuck_duty) {
    const double error = in.motor_error.ToDouble();
    const bool driven = mjc::Abs(in.applied_duty) >= stuck_duty &&
                        (error > kStuckHoldErrorRad || error < -kStuckHoldErrorRad);
    run = (have_previous && driven && in.motor_count == previous) ? run + 1 : 0;
    previous = in.motor_count;
    have_previous = true;
  }
};

MJC_VECTOR_TEST(SupervisorFault, MotorStuckNeedsExactlyMotorStuckTicks) {
  for (const std::uint32_t ticks : {2000u, 7u, 1u}) {
    for (const double duty : {0.5, -0.5}) {
      // Setup: the motor turns (driven), then its count freezes under the same duty.
      SupervisorConfig config;
      config.motor_stuck_ticks = ticks;
      Rig rig(config);
      FrozenCounter counter;
      for (int i = 0; i < 50; ++i) {
        const SupervisorInput in = Sample(0.3, 0.32 + 1e-4 * i, 0.05, 0.0, duty);
        counter.Add(in, config.stuck_duty);
        VT_EXPECT_EQ(F(rig.Check(in)), F(Fault::kNone));
      }
      VT_EXPECT_EQ(counter.run, 0u);
      const SupervisorInput frozen = Sample(0.3, 0.32 + 1e-4 * 49, 0.05, 0.0, duty);
      // Exercise: frozen driven ticks, counted independently.
      int early = 0;
      Fault got = Fault::kNone;
      while (counter.run < ticks) {
        counter.Add(frozen, config.stuck_duty);
        got = rig.Check(frozen);
        if (counter.run < ticks && got != Fault::kNone) ++early;
      }
      // Verify: the ticks-th frozen driven tick faults, not one before.
      VT_EXPECT_EQ(early, 0);
      VT_EXPECT_EQ(F(got), F(Fault::kMotorStuck));
      VT_EXPECT_TRUE(!rig.supervisor.bridge_enabled());
      VT_EXPECT_EQ(rig.state.fault_tick, rig.tick - 1);
      VT_EXPECT_EQ(Feed(rig, Sample(0.3, 0.32, 0.05, 0.0, 0.0), 100), 100);  // latched

      // Clear refuses a visible cause; at the frozen reading it succeeds and the
      // counter restarts: the same number of frozen driven ticks is needed again.
      SupervisorInput bad = frozen;
      bad.torque = Torque::FromDouble(-1.5);
      VT_EXPECT_TRUE(!rig.supervisor.Clear(bad));
      VT_EXPECT_TRUE(rig.supervisor.Clear(frozen));
      VT_EXPECT_TRUE(rig.supervisor.bridge_enabled());
      counter = FrozenCounter{};
      counter.Add(frozen, config.stuck_duty);
      early = 0;
      while (counter.run < ticks) {
        counter.Add(frozen, config.stuck_duty);
        got = rig.Check(frozen);
        if (counter.run < ticks && got != Fault::kNone) ++early;
      }
      VT_EXPECT_EQ(early, 0);
      VT_EXPECT_EQ(F(got), F(Fault::kMotorStuck));
    }
  }
  VT_EXPECT_EQ(F(Fault::kMotorStuck), 111);
}

MJC_VECTOR_TEST(SupervisorFault, MotorStuckCounterRestartsOnMotionOrLowDuty) {
  // Setup
  Rig rig;
  const SupervisorInput a = Sample(0.3, 0.32, 0.05, 0.0, 0.5);
  const SupervisorInput b = Sample(0.3, 0.32 + kMotorCountRad, 0.05, 0.0, 0.5);
  SupervisorInput b_coasting = b;
  b_coasting.applied_duty = Duty::FromDouble(0.1);
  VT_EXPECT_TRUE(a.motor_count + 1 == b.motor_count);
  // Exercise: 1999 frozen driven ticks, one count of motion, 1999 frozen, one tick of
  // low duty, 1999 frozen: never 2000 in a row.
  VT_EXPECT_EQ(Feed(rig, a, 2000), 0);  // the first has no previous sample
  VT_EXPECT_EQ(Feed(rig, b, 2000), 0);
  VT_EXPECT_EQ(F(rig.Check(b_coasting)), F(Fault::kNone));
  VT_EXPECT_EQ(Feed(rig, b, 1999), 0);
  // Verify: the 2000th in a row is the fault.
  VT_EXPECT_EQ(F(rig.Check(b)), F(Fault::kMotorStuck));
}

MJC_VECTOR_TEST(SupervisorFault, MotorHeldAtItsSetpointIsNotStuck) {
  // A pulley held still on its setpoint under load (duty 0.34, the hold against a cable
  // the static friction keeps pressed on the slack edge at α = 1.25): the hold is not
  // a stall, however long. The same frozen count with the loop one LSB further off
  // its setpoint than the tolerance is one, after exactly motor_stuck_ticks.
  for (const double sign : {1.0, -1.0}) {
    const SupervisorConfig c;
    VT_EXPECT_TRUE(c.stuck_hold_error == Angle::Quantize(kStuckHoldErrorRad));
    const double at = sign * c.stuck_hold_error.ToDouble();
    Rig rig;
    const SupervisorInput held = Sample(-0.009, 0.0, -0.03, 0.0, sign * 0.34, at);
    VT_EXPECT_EQ(Feed(rig, held, 5000), 0);  // 500 ms of hold at the tolerance
    SupervisorInput off = held;
    off.motor_error = sign > 0 ? c.stuck_hold_error + Angle::Epsilon()
                               : -c.stuck_hold_error - Angle::Epsilon();
    FrozenCounter counter;
    counter.Add(held, c.stuck_duty);
    int early = 0;
    Fault got = Fault::kNone;
    while (counter.run < c.motor_stuck_ticks) {
      counter.Add(off, c.stuck_duty);
      got = rig.Check(off);
      if (counter.run < c.motor_stuck_ticks && got != Fault::kNone) ++early;
    }
    VT_EXPECT_EQ(early, 0);
    VT_EXPECT_EQ(F(got), F(Fault::kMotorStuck));
  }
}

MJC_VECTOR_TEST(Supervisor, ThresholdsExactlyAtTheLimitPassOneLsbBeyondFaults) {
  const SupervisorConfig c;
  const Angle eps = Angle::Epsilon();
  struct Edge {
    SupervisorInput near, at, beyond;
    Fault want;
  };
  // Each edge: a sample close to the threshold, the sample exactly at it, and one LSB
  // beyond it; every step between them is far below the jump threshold.
  auto joint_at = [](Angle joint) {
    SupervisorInput in = Sample(0.0, 0.0);
    in.joint = joint;
    in.motor = joint;
    return in;
  };
  auto motor_at = [](Angle motor) {
    SupervisorInput in = Sample(1.5, 0.0);
    in.motor = motor;
    return in;
  };
  auto torque_at = [](Torque torque) {
    SupervisorInput in = Rest();
    in.torque = torque;
    return in;
  };
  // The travel over the span at a mean speed of exactly velocity_max: 5 rad/s over 500
  // ticks at 10 kHz is 0.25 rad, which Angle holds exactly.
  const Angle travel_max = Angle::Quantize(c.velocity_max.ToDouble() * kSpanS);
  VT_EXPECT_EQ(travel_max.ToDouble(), 0.25);
  auto travel_of = [](Angle travel) {
    SupervisorInput in = Rest();
    in.joint_travel = travel;
    return in;
  };
  const Angle jn = Angle::FromDouble(0.005);
  const Torque te = Torque::Epsilon();
  const Edge edges[] = {
      {joint_at(c.joint_max - jn), joint_at(c.joint_max), joint_at(c.joint_max + eps),
       Fault::kJointAngleLimit},
      {joint_at(c.joint_min + jn), joint_at(c.joint_min), joint_at(c.joint_min - eps),
       Fault::kJointAngleLimit},
      {motor_at(c.motor_max - jn), motor_at(c.motor_max), motor_at(c.motor_max + eps),
       Fault::kMotorAngleLimit},
      {motor_at(c.motor_min + jn), motor_at(c.motor_min), motor_at(c.motor_min - eps),
       Fault::kMotorAngleLimit},
      {torque_at(c.torque_max - Torque::FromDouble(0.01)), torque_at(c.torque_max),
       torque_at(c.torque_max + te), Fault::kTorqueLimit},
      {torque_at(-c.torque_max + Torque::FromDouble(0.01)), torque_at(-c.torque_max),
       torque_at(-c.torque_max - te), Fault::kTorqueLimit},
      {travel_of(travel_max - jn), travel_of(travel_max), travel_of(travel_max + eps),
       Fault::kVelocityLimit},
      {travel_of(-travel_max + jn), travel_of(-travel_max), travel_of(-travel_max - eps),
       Fault::kVelocityLimit},
  };
  for (const Edge& e : edges) {
    // Setup
    Rig rig;
    VT_EXPECT_EQ(Feed(rig, e.near, 10), 0);
    // Exercise and verify: at the threshold for a while, then one LSB beyond.
    VT_EXPECT_EQ(Feed(rig, e.at, 10), 0);
    VT_EXPECT_EQ(F(rig.Check(e.beyond)), F(e.want));
    // The same from a cleared supervisor whose first sample is the edge itself.
    Rig fresh;
    VT_EXPECT_TRUE(fresh.supervisor.Clear(e.at));
    VT_EXPECT_TRUE(!fresh.supervisor.Clear(e.beyond));
  }

  // Jump: a step of exactly joint_jump_max passes, one LSB more faults, both ways.
  for (const int sign : {1, -1}) {
    Rig rig;
    const SupervisorInput start = joint_at(Angle::FromDouble(0.3));
    VT_EXPECT_EQ(Feed(rig, start, 10), 0);
    const Angle step = sign > 0 ? c.joint_jump_max : -c.joint_jump_max;
    const SupervisorInput at = joint_at(start.joint + step);
    VT_EXPECT_EQ(F(rig.Check(at)), F(Fault::kNone));
    const Angle more = sign > 0 ? step + eps : step - eps;
    VT_EXPECT_EQ(F(rig.Check(joint_at(at.joint + more))), F(Fault::kJointJump));
  }

  // Joint stuck: the motor walks with the joint count frozen, to exactly
  // stuck_motor_travel from where the count last changed (no fault), then one LSB more.
  for (const int sign : {1, -1}) {
    Rig rig;
    SupervisorInput in = Sample(0.3, 0.0, 0.05, 0.0, 0.5);
    VT_EXPECT_EQ(F(rig.Check(Sample(0.29, 0.0))), F(Fault::kNone));
    VT_EXPECT_EQ(F(rig.Check(in)), F(Fault::kNone));  // count changes here, motor 0
    const Angle travel = sign > 0 ? c.stuck_motor_travel : -c.stuck_motor_travel;
    int early = 0;
    for (int i = 1; i <= 100; ++i) {
      in.motor = Angle::FromRaw(
          static_cast<std::int32_t>(static_cast<std::int64_t>(travel.raw()) * i / 100));
      ++in.motor_count;
      if (rig.Check(in) != Fault::kNone) ++early;
    }
    VT_EXPECT_EQ(early, 0);
    VT_EXPECT_TRUE(in.motor == travel);
    in.motor = sign > 0 ? travel + eps : travel - eps;
    ++in.motor_count;
    VT_EXPECT_EQ(F(rig.Check(in)), F(Fault::kJointStuck));
  }

  // Stuck duty: |duty| = stuck_duty counts as driven, one LSB less does not.
  for (const int sign : {1, -1}) {
    const Duty at = sign > 0 ? c.stuck_duty : -c.stuck_duty;
    const Duty below = sign > 0 ? at - Duty::Epsilon() : at + Duty::Epsilon();
    SupervisorInput in = Rest();
    in.applied_duty = below;
    Rig weak;
    VT_EXPECT_EQ(Feed(weak, in, 10000), 0);
    in.applied_duty = at;
    Rig driven;
    VT_EXPECT_EQ(Feed(driven, in, static_cast<int>(c.motor_stuck_ticks)), 0);
    VT_EXPECT_EQ(F(driven.Check(in)), F(Fault::kMotorStuck));  // tick 2001: 2000 frozen
  }
}

MJC_VECTOR_TEST(Supervisor, SimultaneousCausesReportTheFirstInRangeOrder) {
  // Setup: every visible cause at once (and a 1.4 rad jump from the resting history),
  // then each reported cause removed in turn: the next is the next in range order.
  SupervisorInput in = Sample(1.7, 2.1, 1.5, 6.0, 0.9);
  in.tick_overrun = true;
  in.external = Fault::kCommandTimeout;
  in.joint_status = JointFrameStatus::kParityError;
  const Fault order[] = {Fault::kJointParity,     Fault::kJointErrorFlag,
                         Fault::kJointJump,       Fault::kJointAngleLimit,
                         Fault::kMotorAngleLimit, Fault::kTorqueLimit,
                         Fault::kVelocityLimit,   Fault::kTickOverrun,
                         Fault::kCommandTimeout,  Fault::kNone};
  bool with_history = true;
  for (const Fault want : order) {
    Rig rig;
    if (with_history) VT_EXPECT_EQ(Feed(rig, Rest(), 10), 0);
    // Exercise and verify
    VT_EXPECT_EQ(F(rig.Check(in)), F(want));
    VT_EXPECT_EQ(rig.supervisor.bridge_enabled(), want == Fault::kNone);
    switch (want) {
      case Fault::kJointParity:
        in.joint_status = JointFrameStatus::kErrorFlag;
        break;
      case Fault::kJointErrorFlag:
        in.joint_status = JointFrameStatus::kOk;
        break;
      case Fault::kJointJump:
        with_history = false;
        break;  // no history, no jump
      case Fault::kJointAngleLimit:
        in.joint = Rest().joint;
        break;
      case Fault::kMotorAngleLimit:
        in.motor = Rest().motor;
        break;
      case Fault::kTorqueLimit:
        in.torque = Rest().torque;
        break;
      case Fault::kVelocityLimit:
        in.joint_travel = Angle{};
        break;
      case Fault::kTickOverrun:
        in.tick_overrun = false;
        break;
      case Fault::kCommandTimeout:
        in.external = Fault::kNone;
        break;
      default:
        break;
    }
  }
}

// The joint on a slack cable: the cable follows c = A·sin(ωt); the joint is dragged
// through a play of ±1° (so its count stands still while the cable takes up 2° at
// each reversal); the motor pulley leads the cable by the spring's deflection τ/K under
// an interaction torque τ = 0.15·sin(ωt + 0.5) N·m; the duty is 0.55 + 0.2·sin(2ωt),
// always "driven", so every reversal of the motor is a run of frozen driven ticks.
MJC_VECTOR_TEST(Supervisor, HealthySlowSinusoidWithSlackRaisesNothing) {
  // Setup
  constexpr int kTicks = 100000;  // 10 s at 10 kHz: one period
  constexpr double kAmplitude = 1.2;
  constexpr double kOmega = 2.0 * std::numbers::pi * 0.1;  // 0.1 Hz
  constexpr double kDt = 1e-4;
  constexpr double kSlack = std::numbers::pi / 180.0;  // half of the 2° play
  constexpr double kStiffness = 0.63;
  // sin/cos of one tick's phase step and of 0.5 rad by their series (no libm).
  auto sin_series = [](double x) {
    double term = x, sum = x;
    for (int n = 1; n < 12; ++n) {
      term *= -x * x / ((2.0 * n) * (2.0 * n + 1.0));
      sum += term;
    }
    return sum;
  };
  auto cos_series = [](double x) {
    double term = 1.0, sum = 1.0;
    for (int n = 1; n < 12; ++n) {
      term *= -x * x / ((2.0 * n - 1.0) * (2.0 * n));
      sum += term;
    }
    return sum;
  };
  const double s1 = sin_series(kOmega * kDt), c1 = cos_series(kOmega * kDt);
  const double sh = sin_series(0.5), ch = cos_series(0.5);
  double sin_wt = 0.0, cos_wt = 1.0;  // ωt

  Rig rig;
  const SupervisorConfig& c = rig.config;
  double joint = 0.0;
  // θ_j of the last kSpanTicks ticks, for the travel over the span (the joint rests at
  // 0 before the run, as a board's ring starts full of its first reading).
  // Static: 4 KB is more than the Cortex-M4 test's stack should carry.
  static double history[kSpanTicks];
  for (double& h : history) h = 0.0;
  int faults = 0;
  // What the scenario puts next to each threshold, from the samples themselves.
  FrozenCounter frozen;
  std::uint32_t longest_frozen = 0;
  Angle most_travel_with_count_frozen, largest_step, previous_joint, motor_at_change;
  AngularVelocity peak_velocity;
  Torque peak_torque;
  std::uint16_t last_count = 0;
  for (int t = 0; t < kTicks; ++t) {
    // The model at tick t.
    const double cable = kAmplitude * sin_wt;
    if (cable - joint > kSlack) joint = cable - kSlack;
    if (cable - joint < -kSlack) joint = cable + kSlack;
    const double torque = 0.15 * (sin_wt * ch + cos_wt * sh);
    const double motor = cable + torque * (1.0 / kStiffness);
    SupervisorInput in = Sample(joint, motor, torque, 0.0, 0.55 + 0.4 * sin_wt * cos_wt);
    double& span_ago = history[static_cast<std::uint32_t>(t) % kSpanTicks];
    in.joint_travel = in.joint - Angle::Quantize(span_ago);
    span_ago =
        static_cast<double>(RoundToInt(joint * kJointCountsPerRad)) * kJointCountRad;

    // Exercise
    if (rig.Check(in) != Fault::kNone) ++faults;

    frozen.Add(in, c.stuck_duty);
    if (frozen.run > longest_frozen) longest_frozen = frozen.run;
    if (t == 0 || in.joint_count != last_count) motor_at_change = in.motor;
    last_count = in.joint_count;
    const Angle travel = mjc::Abs(in.motor - motor_at_change);
    if (travel > most_travel_with_count_frozen) most_travel_with_count_frozen = travel;
    const Angle step = mjc::Abs(in.joint - previous_joint);
    if (t > 0 && step > largest_step) largest_step = step;
    previous_joint = in.joint;
    const AngularVelocity mean =
        AngularVelocity::Quantize(in.joint_travel.ToDouble() / kSpanS);
    if (mjc::Abs(mean) > peak_velocity) peak_velocity = mjc::Abs(mean);
    if (mjc::Abs(in.torque) > peak_torque) peak_torque = mjc::Abs(in.torque);

    // Advance the phase by one tick.
    const double s = sin_wt * c1 + cos_wt * s1;
    cos_wt = cos_wt * c1 - sin_wt * s1;
    sin_wt = s;
  }

  // Verify: nothing raised, the bridge stayed on.
  VT_EXPECT_EQ(faults, 0);
  VT_EXPECT_TRUE(rig.supervisor.bridge_enabled());
  // The scenario came close to the stuck detectors without reaching them: the motor
  // took up the whole 2° of slack (plus the spring's change) with the joint count
  // frozen (0.069 rad), and its count stood still under drive for many ticks at the
  // reversals (154).
  VT_EXPECT_TRUE(most_travel_with_count_frozen > Angle::Quantize(2.0 * kSlack));
  VT_EXPECT_TRUE(most_travel_with_count_frozen < c.stuck_motor_travel);
  VT_EXPECT_TRUE(longest_frozen >= 100);
  VT_EXPECT_TRUE(longest_frozen < c.motor_stuck_ticks);
  VT_EXPECT_TRUE(largest_step > Angle{} && largest_step < c.joint_jump_max);
  VT_EXPECT_TRUE(peak_velocity > AngularVelocity::FromDouble(0.7) &&
                 peak_velocity < c.velocity_max);
  VT_EXPECT_TRUE(peak_torque > Torque::FromDouble(0.14) && peak_torque < c.torque_max);
  // One full period: the phase recurrence came back to its start.
  VT_EXPECT_NEAR(sin_wt, 0.0, 1e-9);
}

}  // namespace
