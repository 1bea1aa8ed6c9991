// The board's CAN side against scripted frames: commands and configs in, replies,
// telemetry at their rates, window summaries and faults out; malformed frames counted
// and dropped; the streamed-setpoint timeout stopping the motor. Every frame the node
// sends is decoded with the protocol codec.
#include <cstdint>

#include "mjc/app/can_node.h"
#include "vector_test.h"

namespace {

using namespace mjc;
using namespace mjc::app;
using namespace mjc::protocol;

struct QuietIo {
  Sample ISR_Read() {
    Sample s;
    s.joint_frame = EncodeJointFrame(0, false);
    return s;
  }
  void ISR_Write(const Actuation& a) { written = a; }
  Actuation written;
};

BacklashConfig Calibration() {
  BacklashConfig b;
  b.c_right = Angle::FromDouble(0.0175);
  b.c_left = Angle::FromDouble(-0.0175);
  return b;
}

struct Board {
  Board() : app(ControlConfig{}), node(&app, CanNodeConfig{}) {}
  // Ticks the app and polls the node; counts what it sent by function code.
  void Run(int ticks) {
    for (int i = 0; i < ticks; ++i) {
      app.ISR_Tick(io);
      node.Poll();
      CanFrame f;
      while (node.PopTx(&f)) {
        ++sent[FunctionOf(f.id)];
        last[FunctionOf(f.id)] = f;
      }
    }
  }
  JointApp app;
  CanNode node;
  QuietIo io;
  std::uint32_t sent[128] = {};
  CanFrame last[128] = {};
};

template <class M>
M Last(const Board& b) {
  M m{};
  (void)Decode(b.last[static_cast<std::uint8_t>(Message<M>::kFunction)], &m);
  return m;
}
template <class M>
std::uint32_t Sent(const Board& b) {
  return b.sent[static_cast<std::uint8_t>(Message<M>::kFunction)];
}

void Calibrate(Board& b) {
  b.app.SetCalibration(Calibration());
  b.Run(1);
}

MJC_VECTOR_TEST(CanNode, TrialStartedOverCanWithReplyTelemetryAndWindows) {
  static Board b;
  Calibrate(b);
  TrialConfig t;
  t.amplitude = Angle::FromDouble(0.2);
  t.frequency_mHz = 10000;  // 10 Hz: short cycles
  t.repetitions = 2;
  t.rest_100ms = 0;
  b.node.HandleFrame(Encode(t, 1));
  b.node.HandleFrame(Encode(Command{CommandCode::kStartTrial, 7}, 1));
  b.Run(1);
  const protocol::CommandResult r = Last<protocol::CommandResult>(b);
  VT_EXPECT_TRUE(r.outcome == CommandOutcomeCode::kAccepted);
  VT_EXPECT_EQ(r.sequence, 7);
  VT_EXPECT_TRUE(b.app.state() == AppState::kRunning);
  b.Run(2999);
  // 3000 ticks: 1 kHz angles every 10 ticks, 10 Hz heartbeat every 1000.
  VT_EXPECT_TRUE(Sent<TelemetryAngles>(b) >= 299 && Sent<TelemetryAngles>(b) <= 301);
  VT_EXPECT_TRUE(Sent<Heartbeat>(b) >= 3 && Sent<Heartbeat>(b) <= 6);
  // Two cycles: two flexion and two extension windows, five frames each.
  VT_EXPECT_EQ(Sent<WindowHeader>(b), 4u);
  VT_EXPECT_EQ(Sent<WindowEnergy>(b), 4u);
  VT_EXPECT_EQ(Sent<WindowTicks>(b), 4u);
  VT_EXPECT_TRUE(b.app.state() == AppState::kIdle);
  VT_EXPECT_EQ(b.node.counters().tx_dropped, 0u);
}

MJC_VECTOR_TEST(CanNode, TrialRefusedWithoutConfigOrCalibration) {
  static Board b;
  b.node.HandleFrame(Encode(Command{CommandCode::kStartTrial, 1}, 1));
  b.Run(1);
  VT_EXPECT_TRUE(Last<protocol::CommandResult>(b).outcome ==
                 CommandOutcomeCode::kRefusedInvalid);
  TrialConfig t;
  t.amplitude = Angle::FromDouble(0.2);
  b.node.HandleFrame(Encode(t, 1));
  b.node.HandleFrame(Encode(Command{CommandCode::kStartTrial, 2}, 1));
  b.Run(1);
  VT_EXPECT_TRUE(Last<protocol::CommandResult>(b).outcome ==
                 CommandOutcomeCode::kRefusedUncalibrated);
  VT_EXPECT_TRUE(b.app.state() == AppState::kIdle);
}

MJC_VECTOR_TEST(CanNode, MalformedAndForeignFramesAreCountedAndDropped) {
  static Board b;
  CanFrame bad = Encode(Command{CommandCode::kStop, 1}, 1);
  bad.length = 1;
  b.node.HandleFrame(bad);
  bad = Encode(Command{CommandCode::kStop, 1}, 1);
  bad.data[0] = 99;  // no such command
  b.node.HandleFrame(bad);
  b.node.HandleFrame(Encode(Command{CommandCode::kStop, 1}, 2));  // another node's
  b.node.HandleFrame(Encode(Heartbeat{}, 1));                     // a board's message
  VT_EXPECT_EQ(b.node.counters().malformed[static_cast<int>(DecodeError::kWrongLength)],
               1u);
  VT_EXPECT_EQ(
      b.node.counters().malformed[static_cast<int>(DecodeError::kFieldOutOfRange)], 1u);
  VT_EXPECT_EQ(b.node.counters().ignored, 2u);
  VT_EXPECT_EQ(b.node.counters().handled, 0u);
  b.Run(1);
  VT_EXPECT_EQ(Sent<protocol::CommandResult>(b), 0u);  // nothing was acted on
}

MJC_VECTOR_TEST(CanNode, SilentStreamStopsTheMotorAndLatches) {
  static Board b;
  Calibrate(b);
  b.node.HandleFrame(Encode(Command{CommandCode::kStartStream, 3}, 1));
  b.Run(1);
  VT_EXPECT_TRUE(b.app.state() == AppState::kRunning);
  // Setpoints every 5 ms for 0.5 s: healthy.
  for (int i = 0; i < 100; ++i) {
    b.node.HandleFrame(
        Encode(Setpoint{Angle::FromRaw(16777 * i), static_cast<std::uint16_t>(i)}, 1));
    b.Run(50);
  }
  VT_EXPECT_TRUE(b.app.state() == AppState::kRunning);
  VT_EXPECT_TRUE(b.io.written.bridge_enabled);
  // Then silence: stopped within the 100 ms timeout plus one tick, latched.
  int ticks = 0;
  while (b.app.state() == AppState::kRunning && ticks < 2000) {
    b.Run(1);
    ++ticks;
  }
  VT_EXPECT_TRUE(ticks <= 1000 - 50 + 2);
  VT_EXPECT_TRUE(b.app.state() == AppState::kFault);
  VT_EXPECT_TRUE(!b.io.written.bridge_enabled);
  VT_EXPECT_TRUE(Last<FaultEvent>(b).fault == Fault::kCommandTimeout);
  VT_EXPECT_EQ(b.node.counters().stream_timeouts, 1u);
  b.Run(100);
  VT_EXPECT_TRUE(b.app.state() == AppState::kFault);
  // Clearing removes the cause and the fault.
  b.node.HandleFrame(Encode(Command{CommandCode::kClearFaults, 4}, 1));
  b.Run(2);
  VT_EXPECT_TRUE(b.app.state() == AppState::kIdle);
}

MJC_VECTOR_TEST(CanNode, ParametersReadWriteAndRefusals) {
  static Board b;
  b.node.HandleFrame(Encode(ParamWrite{ParamId::kTelemetryAnglesHz, 100}, 1));
  b.Run(1);
  VT_EXPECT_TRUE(Last<ParamValue>(b).status == ParamStatus::kOk);
  VT_EXPECT_EQ(b.node.config().angles_hz, 100);
  const std::uint32_t before = Sent<TelemetryAngles>(b);
  b.Run(1000);
  VT_EXPECT_TRUE(Sent<TelemetryAngles>(b) - before >= 9 &&
                 Sent<TelemetryAngles>(b) - before <= 11);
  b.node.HandleFrame(Encode(ParamWrite{ParamId::kTelemetryAnglesHz, 20000}, 1));
  b.Run(1);
  VT_EXPECT_TRUE(Last<ParamValue>(b).status == ParamStatus::kOutOfRange);
  VT_EXPECT_EQ(b.node.config().angles_hz, 100);
  // A control gain: written while idle, refused while running.
  b.node.HandleFrame(Encode(ParamWrite{ParamId::kPositionKp, 40 << 16}, 1));
  b.Run(2);
  VT_EXPECT_TRUE(Last<ParamValue>(b).status == ParamStatus::kOk);
  VT_EXPECT_EQ(b.app.control().config().position.kp.raw(), 40 << 16);
  b.node.HandleFrame(Encode(ParamWrite{ParamId::kVelocityWindow, 500}, 1));  // even
  b.Run(1);
  VT_EXPECT_TRUE(Last<ParamValue>(b).status == ParamStatus::kOutOfRange);
  Calibrate(b);
  b.node.HandleFrame(Encode(Command{CommandCode::kStartStream, 5}, 1));
  b.Run(1);
  b.node.HandleFrame(Encode(ParamWrite{ParamId::kPositionKp, 1 << 16}, 1));
  b.Run(1);
  VT_EXPECT_TRUE(Last<ParamValue>(b).status == ParamStatus::kRefusedNotIdle);
  b.node.HandleFrame(Encode(ParamRead{ParamId::kPositionKp}, 1));
  b.Run(1);
  VT_EXPECT_EQ(Last<ParamValue>(b).value, 40 << 16);
}

}  // namespace
