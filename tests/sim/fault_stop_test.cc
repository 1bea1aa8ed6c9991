// Every fault the board stops for, injected at its real cause on the simulated board
// (the causes, and the tick each time counts from: tests/sim/safe_stop_rig.h). Per
// fault: the bridge is off within the fault's goal, the FaultEvent on the bus carries
// the stable code and the stop tick, the fault stays latched, a ClearFaults is refused
// while the cause persists and returns the board to idle once the cause is gone.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <numbers>

#include "mjc/plant/params.h"
#include "safe_stop_rig.h"

namespace {

using namespace mjc;
using namespace mjc::safe_stop;
using protocol::CommandOutcomeCode;

// Whether the case's cause can still be there when the clear is judged (a corrupted
// frame or overrun kept up, a limit still crossed). A frozen encoder persists too, but
// the supervisor cannot judge it without motion, and lost messages are events.
enum class Persists : bool { kNo = false, kYes = true };

// The common checks; `code` is the stable number from supervisor.h, written out so a
// renumbering fails here.
Measurement MeasureAndCheck(FaultCase c, std::uint16_t code, Persists persists) {
  const Measurement m = Measure(c);
  EXPECT_TRUE(m.error.empty()) << m.error;
  EXPECT_EQ(static_cast<std::uint16_t>(ExpectedFault(c)), code);
  EXPECT_EQ(static_cast<std::uint16_t>(m.raised), code) << "latched in the stop tick";

  // Reported once, on the bus, decoded by the protocol's own Decode.
  EXPECT_EQ(m.fault_frames, 1);
  EXPECT_EQ(static_cast<std::uint16_t>(m.frame_fault), code);
  EXPECT_EQ(m.frame_tick, m.stop_tick);

  // Latched: bridge off, kFault, on every tick up to the accepted clear (which comes
  // after 0.9 s of recovery at least).
  EXPECT_TRUE(m.latched);
  EXPECT_GE(m.latched_ticks, 9000u);

  EXPECT_EQ(m.refusal_tried, persists == Persists::kYes);
  if (persists == Persists::kYes) {
    EXPECT_TRUE(m.cause_present_at_refusal)
        << "the refusal was not tested against the cause";
    EXPECT_EQ(m.refusal_outcome, CommandOutcomeCode::kRefusedFaultActive);
    EXPECT_TRUE(m.fault_after_refusal);
  }

  EXPECT_TRUE(m.cause_gone_at_clear);
  EXPECT_TRUE(m.clear_answered);
  EXPECT_EQ(m.clear_outcome, CommandOutcomeCode::kAccepted);
  EXPECT_TRUE(m.idle_after_clear);

  std::printf("[ safe stop] %-20s %5lld ticks (%5.1f ms)", Name(c),
              static_cast<long long>(m.stop_ticks()), m.stop_ms());
  if (m.detectable_tick != m.cause_tick) {
    std::printf(", %lld after the first sample its rule can judge",
                static_cast<long long>(m.detect_to_stop_ticks()));
  }
  std::printf("\n");
  return m;
}

// Local faults: the actuation written in the tick whose sample carries the fault has
// the bridge off.
TEST(FaultStop, JointParityStopsInTheSameTick) {
  EXPECT_EQ(MeasureAndCheck(FaultCase::kJointParity, 100, Persists::kYes).stop_ticks(),
            0);
}
TEST(FaultStop, JointErrorFlagStopsInTheSameTick) {
  EXPECT_EQ(MeasureAndCheck(FaultCase::kJointErrorFlag, 101, Persists::kYes).stop_ticks(),
            0);
}
TEST(FaultStop, JointJumpStopsInTheSameTick) {
  EXPECT_EQ(MeasureAndCheck(FaultCase::kJointJump, 102, Persists::kNo).stop_ticks(), 0);
}
TEST(FaultStop, TickOverrunStopsInTheSameTick) {
  EXPECT_EQ(MeasureAndCheck(FaultCase::kTickOverrun, 300, Persists::kYes).stop_ticks(),
            0);
}

// A frozen count is only a fault once it is implausible: the stop comes in the tick
// whose sample first meets the supervisor's rule (evaluated on the raw samples).
TEST(FaultStop, StuckJointStopsInTheTickItIsImplausible) {
  const Measurement m = MeasureAndCheck(FaultCase::kJointStuck, 103, Persists::kNo);
  EXPECT_EQ(m.detect_to_stop_ticks(), 0);
  // Frozen at the flexion peak (+0.435 rad), the motor travels 0.87 rad to the
  // extension peak within the half cycle (1 s), beyond stuck_motor_travel (0.6 rad).
  EXPECT_GT(m.stop_ticks(), 0);
  EXPECT_LE(m.stop_ticks(), 10000);
}
TEST(FaultStop, StuckMotorStopsAfterItsEvidence) {
  const Measurement m = MeasureAndCheck(FaultCase::kMotorStuck, 111, Persists::kNo);
  EXPECT_EQ(m.detect_to_stop_ticks(), 0);
  // The rule needs motor_stuck_ticks (2000) frozen ticks under |duty| >= 0.3. The
  // position loop (kp 40 /rad) puts 0.3 on a 7.5 mrad error, which the setpoint moving
  // at 1.3 rad/s opens within 6 ms: the evidence starts within 100 ticks.
  const std::int64_t rule = SupervisorConfig{}.motor_stuck_ticks;
  EXPECT_GE(m.stop_ticks(), rule);
  EXPECT_LE(m.stop_ticks(), rule + 100);
}

// Limits: from the first sample beyond the limit (the reference on the raw samples).
TEST(FaultStop, JointAngleLimitStopsInTheSameTick) {
  EXPECT_EQ(
      MeasureAndCheck(FaultCase::kJointAngleLimit, 200, Persists::kYes).stop_ticks(), 0);
}
TEST(FaultStop, MotorAngleLimitStopsInTheSameTick) {
  EXPECT_EQ(
      MeasureAndCheck(FaultCase::kMotorAngleLimit, 201, Persists::kYes).stop_ticks(), 0);
}
TEST(FaultStop, TorqueLimitStopsInTheSameTick) {
  EXPECT_EQ(MeasureAndCheck(FaultCase::kTorqueLimit, 202, Persists::kYes).stop_ticks(),
            0);
}

// The velocity limit judges the joint's mean speed over the last delay_ticks() ticks,
// its travel over that span: no model, no filter, the instant half the span old. It
// stops in the tick that mean (recomputed in double from the raw joint frames) first
// exceeds the limit, which is later than the plant truth's crossing: a rising speed's
// mean over the span passes the limit about half a span after the speed itself. The
// reference agrees with the board within kVelocityReferenceTolRadS: the board stops no
// earlier than the reference comes within it of the limit, and no later than the tick
// after the reference is beyond the limit by more. The whole span past the crossing is
// the latest it may stop.
TEST(FaultStop, VelocityLimitStopsWithinItsSpan) {
  const Measurement m = MeasureAndCheck(FaultCase::kVelocityLimit, 203, Persists::kYes);
  EXPECT_GE(m.detect_to_stop_ticks(), 0);
  EXPECT_LE(m.velocity_before_stop, kVelocityMaxRadS + kVelocityReferenceTolRadS);
  EXPECT_GE(m.velocity_at_stop, kVelocityMaxRadS - kVelocityReferenceTolRadS);
  EXPECT_EQ(m.delay_ticks, 500);
  EXPECT_GT(m.stop_ticks(), 0);
  EXPECT_LE(m.stop_ticks(), m.delay_ticks);
  // What the rule judges is the joint's mean speed: at the stop the plant truth's mean
  // over the same span is at the limit within the two readings' noise (the σ of
  // subject1's joint encoder and its quantisation, on each reading; 4σ).
  const double sigma_counts =
      mjc::plant::LoadPlantParams("subject1").sensors.joint_noise_counts;
  const double count_rad = 2.0 * std::numbers::pi / 16384.0;
  const double span_s = static_cast<double>(m.delay_ticks) / m.tick_hz;
  const double noise_rad_s =
      std::sqrt(2.0 * (sigma_counts * sigma_counts + 1.0 / 12.0)) * count_rad / span_s;
  EXPECT_NEAR(m.truth_mean_at_stop, kVelocityMaxRadS, 4.0 * noise_rad_s);
}

// Lost messages: within the configured timeout, plus the main loop's poll and the
// next tick; never before it.
TEST(FaultStop, CommandTimeoutStopsWithin100ms) {
  const Measurement m = MeasureAndCheck(FaultCase::kCommandTimeout, 301, Persists::kNo);
  const std::int64_t timeout = std::int64_t{m.stream_timeout_ms} * m.tick_hz / 1000;
  EXPECT_GT(m.stop_ticks(), timeout);
  EXPECT_LE(m.stop_ticks(), timeout + m.tick_hz / 1000);
  EXPECT_LE(m.stop_ms(), 100.0);  // the goal for lost commands
}
TEST(FaultStop, HostHeartbeatLostStopsWithinItsTimeout) {
  const Measurement m =
      MeasureAndCheck(FaultCase::kHostHeartbeatLost, 302, Persists::kNo);
  const std::int64_t timeout = std::int64_t{m.host_timeout_ms} * m.tick_hz / 1000;
  EXPECT_GT(m.stop_ticks(), timeout);
  EXPECT_LE(m.stop_ticks(), timeout + m.tick_hz / 1000);
}
TEST(FaultStop, BusOffStopsInTheNextTick) {
  EXPECT_LE(MeasureAndCheck(FaultCase::kCanBusOff, 303, Persists::kNo).stop_ticks(), 1);
}
// The broadcast stop: the main loop takes the frame, the next tick latches the fault
// and writes the bridge off.
TEST(FaultStop, EmergencyStopStopsInTheNextTick) {
  EXPECT_EQ(MeasureAndCheck(FaultCase::kEmergencyStop, 305, Persists::kNo).stop_ticks(),
            1);
}

}  // namespace
