// The board's CAN side against scripted frames: commands and configs in, replies,
// telemetry at their rates, window summaries and faults out; malformed frames counted
// and dropped; the streamed-setpoint timeout stopping the motor. Every frame the node
// sends is decoded with the protocol codec.
#include <algorithm>
#include <cstdint>

#include "mjc/app/can_node.h"
#include "mjc/app/joint_board.h"
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

mjc::Calibration TestCalibration() {
  mjc::Calibration c;
  c.backlash.c_right = Angle::FromDouble(0.0175);
  c.backlash.c_left = Angle::FromDouble(-0.0175);
  return c;
}

struct Board {
  explicit Board(const CanNodeConfig& config = {})
      : app(ControlConfig{}), service(&app, nullptr), node(&service, config) {}
  // Ticks the app and polls the node; counts what it sent by function code.
  void Run(int ticks) {
    for (int i = 0; i < ticks; ++i) {
      app.ISR_Tick(io);
      service.Poll();
      node.Poll();
      Drain();
    }
  }
  // Collects what the node has queued (replies given without waiting for a tick).
  void Drain() {
    CanFrame f;
    while (node.PopTx(&f)) {
      ++sent[FunctionOf(f.id)];
      last[FunctionOf(f.id)] = f;
      protocol::CommandResult r;
      if (FunctionOf(f.id) == static_cast<std::uint8_t>(Function::kCommandResult) &&
          Decode(f, &r) == DecodeError::kOk && results_n < 16) {
        results[results_n++] = r;
      }
      // Window starts and ends in the order sent, decoded.
      WindowStart w;
      if (Decode(f, &w) == DecodeError::kOk && starts_n < 16) starts[starts_n++] = w;
      WindowTicks t;
      if (Decode(f, &t) == DecodeError::kOk && ends_n < 16) ends[ends_n++] = t;
    }
  }
  JointApp app;
  service::JointService service;
  CanNode node;
  QuietIo io;
  std::uint32_t sent[128] = {};
  CanFrame last[128] = {};
  protocol::CommandResult results[16] = {};  // every reply, in order
  int results_n = 0;
  WindowStart starts[16] = {};
  int starts_n = 0;
  WindowTicks ends[16] = {};
  int ends_n = 0;
};

template <class M>
M Last(::mjc::vt::Context& vt_context, const Board& b) {
  const auto function = static_cast<std::uint8_t>(Message<M>::kFunction);
  M m{};
  // A message never sent, or one that does not decode, fails here rather than
  // yielding a zeroed struct the caller might accept.
  VT_EXPECT_TRUE(b.sent[function] > 0);
  VT_EXPECT_TRUE(Decode(b.last[function], &m) == DecodeError::kOk);
  return m;
}
template <class M>
std::uint32_t Sent(const Board& b) {
  return b.sent[static_cast<std::uint8_t>(Message<M>::kFunction)];
}

void Calibrate(Board& b) {
  b.app.SetCalibration(TestCalibration());
  b.Run(1);
}

// `config` and a StartTrial from the host (`sequence`, commanded by `session`, 0: none),
// then `ticks` ticks.
void StartTrial(Board& b, const TrialConfig& config, std::uint8_t sequence, int ticks = 1,
                SessionId session = 0) {
  b.node.HandleFrame(Encode(config, 1));
  b.node.HandleFrame(Encode(
      Command{CommandCode::kStartTrial, sequence, session, ConfigDigestOf(config)}, 1));
  b.Run(ticks);
}

MJC_VECTOR_TEST(CanNode, TrialStartedOverCanWithReplyTelemetryAndWindows) {
  static Board b;
  Calibrate(b);
  TrialConfig t;
  t.amplitude = Angle::FromDouble(0.2);
  t.frequency_mHz = 10000;  // 10 Hz: short cycles
  t.repetitions = 2;
  t.rest_100ms = 0;
  StartTrial(b, t, 7);
  const protocol::CommandResult r = Last<protocol::CommandResult>(vt_context, b);
  VT_EXPECT_TRUE(r.outcome == CommandOutcomeCode::kAccepted);
  VT_EXPECT_EQ(r.sequence, 7);
  VT_EXPECT_TRUE(b.app.state() == BoardState::kRunning);
  b.Run(2999);
  // 3000 ticks: 1 kHz angles every 10 ticks, 10 Hz heartbeat every 1000.
  VT_EXPECT_TRUE(Sent<TelemetryAngles>(b) >= 299 && Sent<TelemetryAngles>(b) <= 301);
  VT_EXPECT_TRUE(Sent<Heartbeat>(b) >= 3 && Sent<Heartbeat>(b) <= 6);
  // Two cycles: two flexion and two extension windows, five frames each.
  VT_EXPECT_EQ(Sent<WindowHeader>(b), 4u);
  VT_EXPECT_EQ(Sent<WindowEnergy>(b), 4u);
  VT_EXPECT_EQ(Sent<WindowTicks>(b), 4u);
  // Each announced at its start, on the tick its summary names as its start: flexion,
  // extension, flexion, extension. The trajectory's quarter period at 10 Hz is 250
  // ticks, so the windows start 500 ticks apart.
  VT_EXPECT_EQ(b.starts_n, 4);
  VT_EXPECT_EQ(b.ends_n, 4);
  for (int i = 0; i < 4 && i < b.starts_n && i < b.ends_n; ++i) {
    VT_EXPECT_TRUE(b.starts[i].motion ==
                   (i % 2 == 0 ? Motion::kFlexion : Motion::kExtension));
    VT_EXPECT_EQ(b.starts[i].start_tick, b.ends[i].start_tick);
    if (i > 0) VT_EXPECT_EQ(b.starts[i].start_tick - b.starts[i - 1].start_tick, 500u);
  }
  VT_EXPECT_TRUE(b.app.state() == BoardState::kIdle);
  VT_EXPECT_EQ(b.node.counters().tx_dropped, 0u);
}

MJC_VECTOR_TEST(CanNode, TrialRefusedWithoutConfigOrCalibration) {
  static Board b;
  b.node.HandleFrame(Encode(Command{CommandCode::kStartTrial, 1}, 1));
  b.Run(1);
  VT_EXPECT_TRUE(Last<protocol::CommandResult>(vt_context, b).outcome ==
                 CommandOutcomeCode::kRefusedInvalid);
  TrialConfig t;
  t.amplitude = Angle::FromDouble(0.2);
  StartTrial(b, t, 2);
  VT_EXPECT_TRUE(Last<protocol::CommandResult>(vt_context, b).outcome ==
                 CommandOutcomeCode::kRefusedUncalibrated);
  VT_EXPECT_TRUE(b.app.state() == BoardState::kIdle);
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
  VT_EXPECT_TRUE(b.app.state() == BoardState::kRunning);
  // Setpoints every 5 ms for 0.5 s: healthy.
  for (int i = 0; i < 100; ++i) {
    b.node.HandleFrame(
        Encode(Setpoint{Angle::FromRaw(16777 * i), static_cast<std::uint16_t>(i)}, 1));
    b.Run(50);
  }
  VT_EXPECT_TRUE(b.app.state() == BoardState::kRunning);
  VT_EXPECT_TRUE(b.io.written.bridge_enabled);
  // Then silence: stopped within the 50 ms timeout plus two ticks, latched.
  int ticks = 0;
  while (b.app.state() == BoardState::kRunning && ticks < 2000) {
    b.Run(1);
    ++ticks;
  }
  VT_EXPECT_TRUE(ticks <= 500 - 50 + 2);
  VT_EXPECT_TRUE(b.app.state() == BoardState::kFault);
  VT_EXPECT_TRUE(!b.io.written.bridge_enabled);
  VT_EXPECT_TRUE(Last<FaultEvent>(vt_context, b).fault == Fault::kCommandTimeout);
  VT_EXPECT_EQ(b.node.counters().stream_timeouts, 1u);
  b.Run(100);
  VT_EXPECT_TRUE(b.app.state() == BoardState::kFault);
  // Clearing removes the cause and the fault.
  b.node.HandleFrame(Encode(Command{CommandCode::kClearFaults, 4}, 1));
  b.Run(2);
  VT_EXPECT_TRUE(b.app.state() == BoardState::kIdle);
}

MJC_VECTOR_TEST(CanNode, ParametersReadWriteAndRefusals) {
  static Board b;
  b.node.HandleFrame(Encode(ParamWrite{ParamId::kTelemetryAnglesHz, 100}, 1));
  b.Run(1);
  VT_EXPECT_TRUE(Last<ParamValue>(vt_context, b).status == ParamStatus::kOk);
  VT_EXPECT_EQ(b.node.config().rates.angles_hz, 100);
  const std::uint32_t before = Sent<TelemetryAngles>(b);
  b.Run(1000);
  VT_EXPECT_TRUE(Sent<TelemetryAngles>(b) - before >= 9 &&
                 Sent<TelemetryAngles>(b) - before <= 11);
  b.node.HandleFrame(Encode(ParamWrite{ParamId::kTelemetryAnglesHz, 20000}, 1));
  b.Run(1);
  VT_EXPECT_TRUE(Last<ParamValue>(vt_context, b).status == ParamStatus::kAboveMaximum);
  VT_EXPECT_EQ(Last<ParamValue>(vt_context, b).value, 10000);  // the bound
  VT_EXPECT_EQ(b.node.config().rates.angles_hz, 100);
  // A control gain: written while idle, refused while running.
  b.node.HandleFrame(Encode(ParamWrite{ParamId::kPositionKp, 40 << 16}, 1));
  b.Run(2);
  VT_EXPECT_TRUE(Last<ParamValue>(vt_context, b).status == ParamStatus::kOk);
  VT_EXPECT_EQ(b.app.control().config().position.kp.raw(), 40 << 16);
  b.node.HandleFrame(Encode(ParamWrite{ParamId::kVelocityWindow, 500}, 1));  // even
  b.Run(1);
  VT_EXPECT_TRUE(Last<ParamValue>(vt_context, b).status == ParamStatus::kOutOfRange);
  // A torque limit no sample can meet would latch a fault on every tick: refused.
  const Torque torque_max = b.app.control().config().supervisor.torque_max;
  b.node.HandleFrame(Encode(ParamWrite{ParamId::kTorqueMax, -(1 << 24)}, 1));
  b.Run(1);
  VT_EXPECT_TRUE(Last<ParamValue>(vt_context, b).status == ParamStatus::kBelowMinimum);
  VT_EXPECT_TRUE(b.app.control().config().supervisor.torque_max == torque_max);
  Calibrate(b);
  b.node.HandleFrame(Encode(Command{CommandCode::kStartStream, 5}, 1));
  b.Run(1);
  b.node.HandleFrame(Encode(ParamWrite{ParamId::kPositionKp, 1 << 16}, 1));
  b.Run(1);
  VT_EXPECT_TRUE(Last<ParamValue>(vt_context, b).status == ParamStatus::kRefusedNotIdle);
  b.node.HandleFrame(Encode(ParamRead{ParamId::kPositionKp}, 1));
  b.Run(1);
  VT_EXPECT_EQ(Last<ParamValue>(vt_context, b).value, 40 << 16);
}

MJC_VECTOR_TEST(CanNode, EachCommandIsAnsweredWithItsOwnVerdict) {
  static Board b;
  TrialConfig t;
  t.amplitude = Angle::FromDouble(0.2);
  b.node.HandleFrame(Encode(t, 1));
  // Three commands before one tick: each reply carries its own sequence and verdict.
  b.node.HandleFrame(
      Encode(Command{CommandCode::kStartTrial, 10, 0, ConfigDigestOf(t)}, 1));  // uncal.
  b.node.HandleFrame(Encode(Command{CommandCode::kStop, 11}, 1));
  b.node.HandleFrame(Encode(Command{CommandCode::kClearFaults, 12}, 1));
  b.Run(3);
  VT_EXPECT_EQ(b.results_n, 3);
  VT_EXPECT_EQ(b.results[0].sequence, 10);
  VT_EXPECT_TRUE(b.results[0].outcome == CommandOutcomeCode::kRefusedUncalibrated);
  VT_EXPECT_EQ(b.results[1].sequence, 11);
  VT_EXPECT_TRUE(b.results[1].outcome == CommandOutcomeCode::kAccepted);
  VT_EXPECT_EQ(b.results[2].sequence, 12);
  VT_EXPECT_TRUE(b.results[2].outcome == CommandOutcomeCode::kAccepted);
}

MJC_VECTOR_TEST(CanNode, WindowsLongerThanTheWireFieldAreRefused) {
  static Board b;
  Calibrate(b);
  TrialConfig t;
  t.amplitude = Angle::FromDouble(0.2);
  t.frequency_mHz = 50;  // 10 s half-cycles: 100,000 ticks, beyond the 16-bit offsets
  StartTrial(b, t, 20, 2);
  const protocol::CommandResult r = Last<protocol::CommandResult>(vt_context, b);
  VT_EXPECT_TRUE(r.outcome == CommandOutcomeCode::kRefusedInvalid);
  VT_EXPECT_EQ(r.detail, kDetailWindowTooLong);
  VT_EXPECT_TRUE(b.app.state() == BoardState::kIdle);
  t.frequency_mHz = 80;  // 6.25 s half-cycles: 62,500 ticks fit
  StartTrial(b, t, 21, 2);
  VT_EXPECT_TRUE(Last<protocol::CommandResult>(vt_context, b).outcome ==
                 CommandOutcomeCode::kAccepted);
  VT_EXPECT_TRUE(b.app.state() == BoardState::kRunning);
}

MJC_VECTOR_TEST(CanNode, ParameterWritesKeepTheClockAndTelemetryRunning) {
  static Board b;
  b.Run(2000);
  const std::uint32_t tick_before = Last<Heartbeat>(vt_context, b).tick;
  // A control parameter restarts the control tick; the board's clock must go on.
  b.node.HandleFrame(Encode(ParamWrite{ParamId::kPositionKp, 30 << 16}, 1));
  // A second change before the first is applied is refused as busy, not lost.
  b.node.HandleFrame(Encode(ParamWrite{ParamId::kPositionKd, 1 << 12}, 1));
  b.Drain();
  VT_EXPECT_TRUE(Last<ParamValue>(vt_context, b).status == ParamStatus::kRefusedBusy);
  VT_EXPECT_TRUE(Last<ParamValue>(vt_context, b).id == ParamId::kPositionKd);
  b.Run(1);  // the tick applies the first write and gives its verdict
  VT_EXPECT_TRUE(Last<ParamValue>(vt_context, b).status == ParamStatus::kOk);
  VT_EXPECT_TRUE(Last<ParamValue>(vt_context, b).id == ParamId::kPositionKp);
  const std::uint32_t angles_before = Sent<TelemetryAngles>(b);
  b.Run(2000);
  VT_EXPECT_TRUE(Sent<TelemetryAngles>(b) - angles_before >= 199);
  VT_EXPECT_TRUE(Last<Heartbeat>(vt_context, b).tick > tick_before + 1000);
}

// A trial long enough to outlast the tests below: 0.5 Hz, 5 repetitions, 10 s.
TrialConfig LongTrial() {
  TrialConfig t;
  t.amplitude = Angle::FromDouble(0.2);
  t.frequency_mHz = 500;
  t.repetitions = 5;
  t.rest_100ms = 0;
  return t;
}

// Starts the long trial, commanded by `session` (0: none).
void StartLongTrial(Board& b, std::uint8_t sequence, SessionId session = 0) {
  StartTrial(b, LongTrial(), sequence, 1, session);
}

MJC_VECTOR_TEST(CanNode, LostHostHeartbeatStopsAMotionButNotARest) {
  static Board b;
  Calibrate(b);
  // A motion started without a session (a tool that sends no heartbeats) is not
  // supervised, whoever else sends heartbeats.
  StartLongTrial(b, 1, 0);
  for (int i = 0; i < 5; ++i) {
    b.node.HandleFrame(Encode(HostHeartbeat{static_cast<std::uint8_t>(i), 0x1111}, 1));
    b.Run(1000);
  }
  VT_EXPECT_TRUE(b.app.state() == BoardState::kRunning);
  b.node.HandleFrame(Encode(Command{CommandCode::kStop, 2}, 1));
  b.Run(2);
  // Session 0x1234's heartbeats every 100 ms keep its trial running...
  StartLongTrial(b, 3, 0x1234);
  for (int i = 0; i < 20; ++i) {
    b.node.HandleFrame(Encode(HostHeartbeat{static_cast<std::uint8_t>(i), 0x1234}, 1));
    b.Run(1000);
  }
  VT_EXPECT_TRUE(b.app.state() == BoardState::kRunning);
  // ...and their loss stops it within the 300 ms timeout plus a tick, although another
  // session (a monitor) goes on sending its own.
  int ticks = 0;
  while (b.app.state() == BoardState::kRunning && ticks < 10000) {
    if (ticks % 1000 == 0) {
      b.node.HandleFrame(
          Encode(HostHeartbeat{static_cast<std::uint8_t>(ticks), 0x4321}, 1));
    }
    b.Run(1);
    ++ticks;
  }
  VT_EXPECT_TRUE(ticks <= 3000 - 1000 + 2);
  VT_EXPECT_TRUE(b.app.state() == BoardState::kFault);
  VT_EXPECT_TRUE(!b.io.written.bridge_enabled);
  VT_EXPECT_TRUE(Last<FaultEvent>(vt_context, b).fault == Fault::kHostHeartbeatLost);
  VT_EXPECT_EQ(b.node.counters().host_timeouts, 1u);
  b.node.HandleFrame(Encode(Command{CommandCode::kClearFaults, 4}, 1));
  b.Run(2);
  VT_EXPECT_TRUE(b.app.state() == BoardState::kIdle);
  // A session that goes quiet while the board rests faults nothing, and the next motion
  // (from a tool without a session) is not supervised by the stale one.
  b.node.HandleFrame(Encode(HostHeartbeat{30, 0x1234}, 1));
  b.Run(5000);
  VT_EXPECT_TRUE(b.app.state() == BoardState::kIdle);
  StartLongTrial(b, 5, 0);
  b.Run(5000);
  VT_EXPECT_TRUE(b.app.state() == BoardState::kRunning);
  VT_EXPECT_EQ(b.node.counters().host_timeouts, 1u);
  b.node.HandleFrame(Encode(Command{CommandCode::kStop, 6}, 1));
  b.Run(2);
  // A motion ended by its own commander's stop leaves no supervision behind: the next
  // one of another session is judged by that session's heartbeats alone.
  StartLongTrial(b, 7, 0x1234);
  b.node.HandleFrame(Encode(Command{CommandCode::kStop, 8, 0x1234}, 1));
  b.Run(2);
  VT_EXPECT_TRUE(b.app.state() == BoardState::kIdle);
  StartLongTrial(b, 9, 0x7777);
  for (int i = 0; i < 10; ++i) {
    b.node.HandleFrame(Encode(HostHeartbeat{static_cast<std::uint8_t>(i), 0x7777}, 1));
    b.Run(1000);
  }
  VT_EXPECT_TRUE(b.app.state() == BoardState::kRunning);
  VT_EXPECT_EQ(b.node.counters().host_timeouts, 1u);
}

MJC_VECTOR_TEST(CanNode, OneStartAtATimeAwaitsItsVerdict) {
  static Board b;
  Calibrate(b);
  b.node.HandleFrame(Encode(LongTrial(), 1));
  // Two starts before the tick took the first: the second is refused as busy at once.
  const ConfigDigest digest = ConfigDigestOf(LongTrial());
  b.node.HandleFrame(Encode(Command{CommandCode::kStartTrial, 1, 0x1111, digest}, 1));
  b.node.HandleFrame(Encode(Command{CommandCode::kStartTrial, 2, 0x2222, digest}, 1));
  b.Drain();
  VT_EXPECT_EQ(b.results_n, 1);
  VT_EXPECT_TRUE(b.results[0].sequence == 2 &&
                 b.results[0].outcome == CommandOutcomeCode::kRefusedBusy);
  // The refusal is 0x2222's, and names who holds the board and with what.
  VT_EXPECT_EQ(b.results[0].session, 0x2222);
  VT_EXPECT_EQ(b.results[0].owner, 0x1111);
  VT_EXPECT_EQ(b.results[0].detail, static_cast<std::uint8_t>(CommandCode::kStartTrial));
  b.Run(1);
  VT_EXPECT_EQ(b.results_n, 2);
  VT_EXPECT_TRUE(b.results[1].sequence == 1 &&
                 b.results[1].outcome == CommandOutcomeCode::kAccepted);
  // The motion is session 0x1111's: 0x2222's heartbeats do not keep it.
  for (int i = 0; i < 5 && b.app.state() == BoardState::kRunning; ++i) {
    b.node.HandleFrame(Encode(HostHeartbeat{static_cast<std::uint8_t>(i), 0x2222}, 1));
    b.Run(1000);
  }
  VT_EXPECT_TRUE(b.app.state() == BoardState::kFault);
  VT_EXPECT_EQ(b.node.counters().host_timeouts, 1u);
}

MJC_VECTOR_TEST(CanNode, BusOffStopsTheMotorInTheNextTickAndIsCounted) {
  static Board b;
  Calibrate(b);
  StartLongTrial(b, 1);
  b.Run(1000);
  VT_EXPECT_TRUE(b.io.written.bridge_enabled);
  b.node.OnBusOff();
  b.Run(1);
  VT_EXPECT_TRUE(!b.io.written.bridge_enabled);
  VT_EXPECT_TRUE(b.app.state() == BoardState::kFault);
  VT_EXPECT_TRUE(Last<FaultEvent>(vt_context, b).fault == Fault::kCanBusOff);
  VT_EXPECT_EQ(b.node.counters().bus_off, 1u);
  // The bus is back: the host's clear is accepted.
  b.node.HandleFrame(Encode(Command{CommandCode::kClearFaults, 2}, 1));
  b.Run(2);
  VT_EXPECT_TRUE(b.app.state() == BoardState::kIdle);
}

MJC_VECTOR_TEST(CanNode, StopAllStopsEveryNodeInTheNextTickUntilCleared) {
  static Board b;  // node 1
  Calibrate(b);
  StartLongTrial(b, 1);
  b.Run(1000);
  VT_EXPECT_TRUE(b.io.written.bridge_enabled);
  // Another protocol's frame on identifier 0 (a wrong key) and the stop's function
  // code addressed to one node are no stop: counted as malformed, the trial goes on.
  StopAll wrong;
  wrong.key = 0x00000001;
  b.node.HandleFrame(Encode(wrong, 0));
  CanFrame addressed = Encode(StopAll{}, 0);
  addressed.id = MakeId(static_cast<std::uint8_t>(Function::kStopAll), 1);
  b.node.HandleFrame(addressed);
  b.Run(1);
  VT_EXPECT_TRUE(b.io.written.bridge_enabled);
  VT_EXPECT_EQ(
      b.node.counters().malformed[static_cast<int>(DecodeError::kFieldOutOfRange)], 1u);
  VT_EXPECT_EQ(b.node.counters().malformed[static_cast<int>(DecodeError::kBadNode)], 1u);
  // The broadcast: taken although it names no node, bridge off in the next tick.
  const CanFrame stop = Encode(StopAll{kStopAllKey, 0x5A5A}, 0);
  VT_EXPECT_EQ(stop.id, 0u);
  b.node.HandleFrame(stop);
  b.Run(1);
  VT_EXPECT_TRUE(!b.io.written.bridge_enabled);
  VT_EXPECT_TRUE(b.app.state() == BoardState::kFault);
  VT_EXPECT_TRUE(Last<FaultEvent>(vt_context, b).fault == Fault::kEmergencyStop);
  VT_EXPECT_EQ(b.node.counters().emergency_stops, 1u);
  // Latched: no trial starts until a clear.
  b.Run(1000);
  StartLongTrial(b, 2);
  b.Run(10);
  VT_EXPECT_TRUE(!b.io.written.bridge_enabled);
  VT_EXPECT_TRUE(Last<protocol::CommandResult>(vt_context, b).outcome !=
                 CommandOutcomeCode::kAccepted);
  b.node.HandleFrame(Encode(Command{CommandCode::kClearFaults, 3}, 1));
  b.Run(2);
  VT_EXPECT_TRUE(b.app.state() == BoardState::kIdle);
  // An idle board is stopped all the same: a trial is refused after it.
  b.node.HandleFrame(stop);
  b.Run(2);
  VT_EXPECT_TRUE(b.app.state() == BoardState::kFault);
  VT_EXPECT_EQ(b.node.counters().emergency_stops, 2u);
}

MJC_VECTOR_TEST(CanNode, TellsWhoItIsAtStartAndTenTimesASecond) {
  static JointApp app{ControlConfig{}};
  CanNodeConfig config;
  config.identity.build = 0x1c37bb4au;
  config.identity.dirty = true;
  config.identity.reset_cause = ResetCause::kWatchdog;
  config.identity.instance = 0xBEEF;
  static service::JointService service(&app, nullptr);
  static CanNode node(&service, config);
  QuietIo io;
  int infos = 0;
  BoardInfo last;
  const auto run = [&](int ticks) {
    for (int i = 0; i < ticks; ++i) {
      app.ISR_Tick(io);
      service.Poll();
      node.Poll();
      CanFrame f;
      while (node.PopTx(&f)) {
        if (FunctionOf(f.id) == static_cast<std::uint8_t>(Function::kBoardInfo) &&
            Decode(f, &last) == DecodeError::kOk) {
          ++infos;
        }
      }
    }
  };
  run(1);
  VT_EXPECT_EQ(infos, 1);  // at start
  VT_EXPECT_TRUE(last.build == 0x1c37bb4au && last.dirty &&
                 last.image == ImageKind::kApplication &&
                 last.reset_cause == ResetCause::kWatchdog && last.instance == 0xBEEF);
  run(999);
  VT_EXPECT_EQ(infos, 1);
  run(1);
  VT_EXPECT_EQ(infos, 2);  // and 100 ms later
  // The build is a read-only parameter too.
  node.HandleFrame(Encode(ParamRead{ParamId::kBuildId}, 1));
  CanFrame f;
  ParamValue v;
  bool answered = false;
  while (node.PopTx(&f)) {
    answered = answered || Decode(f, &v) == DecodeError::kOk;
  }
  VT_EXPECT_TRUE(answered && v.status == ParamStatus::kOk &&
                 static_cast<std::uint32_t>(v.value) == 0x1c37bb4au);
  node.HandleFrame(Encode(ParamWrite{ParamId::kBuildId, 1}, 1));
  answered = false;
  while (node.PopTx(&f)) {
    answered = answered || Decode(f, &v) == DecodeError::kOk;
  }
  VT_EXPECT_TRUE(answered && v.status == ParamStatus::kReadOnly);
}

CanNodeConfig WithBootloader() {
  CanNodeConfig c;
  c.bootloader = true;
  return c;
}

MJC_VECTOR_TEST(CanNode, EntersTheBootloaderOnAHoldOnlyAtRest) {
  static Board b(WithBootloader());
  Calibrate(b);
  StartLongTrial(b, 1);
  VT_EXPECT_TRUE(b.app.state() == BoardState::kRunning);
  // While a trial runs: refused, and the board stays where it is.
  b.node.HandleFrame(Encode(BootHold{}, 1));
  b.Drain();
  BootResult r = Last<BootResult>(vt_context, b);
  VT_EXPECT_TRUE(r.request == BootRequest::kHold && r.error == BootError::kMotionRunning);
  VT_EXPECT_TRUE(!b.node.EnterBootloaderNow());
  VT_EXPECT_EQ(b.node.counters().boot_holds_refused, 1u);
  b.Run(100);
  VT_EXPECT_TRUE(b.app.state() == BoardState::kRunning);
  // A frame with another key is not a hold.
  b.node.HandleFrame(Encode(BootHold{0x12345678u}, 1));
  b.Drain();
  VT_EXPECT_TRUE(Last<BootResult>(vt_context, b).error == BootError::kBadRequest);
  VT_EXPECT_TRUE(!b.node.EnterBootloaderNow());
  // Stopped, at rest: accepted. A configuration change waiting for the tick is applied
  // (and would be stored) before the board leaves.
  b.node.HandleFrame(Encode(Command{CommandCode::kStop, 2}, 1));
  b.Run(2);
  VT_EXPECT_TRUE(b.app.state() == BoardState::kIdle);
  b.node.HandleFrame(Encode(ParamWrite{ParamId::kPositionKp, 35 << 16}, 1));
  b.node.HandleFrame(Encode(BootHold{}, 1));
  b.Drain();
  r = Last<BootResult>(vt_context, b);
  VT_EXPECT_TRUE(r.request == BootRequest::kHold && r.error == BootError::kNone);
  VT_EXPECT_TRUE(!b.node.EnterBootloaderNow());
  b.Run(1);
  VT_EXPECT_TRUE(Last<ParamValue>(vt_context, b).status == ParamStatus::kOk);
  VT_EXPECT_TRUE(b.node.EnterBootloaderNow());
  // Leaving: no motion starts any more.
  const int before = b.results_n;
  StartLongTrial(b, 3);
  VT_EXPECT_EQ(b.results_n, before + 1);
  VT_EXPECT_TRUE(b.results[before].outcome == CommandOutcomeCode::kRefusedBusy);
  VT_EXPECT_TRUE(b.app.state() == BoardState::kIdle);
}

MJC_VECTOR_TEST(CanNode, ABoardWithoutABootloaderIgnoresAHold) {
  static Board b;
  b.node.HandleFrame(Encode(BootHold{}, 1));
  b.Run(1);
  VT_EXPECT_EQ(Sent<BootResult>(b), 0u);
  VT_EXPECT_EQ(b.node.counters().ignored, 1u);
  VT_EXPECT_TRUE(!b.node.EnterBootloaderNow());
}

// A port that keeps what the board sent, in order.
class ListPort final : public hal::CanPort {
 public:
  CanFrame in[4];
  int in_n = 0;
  int in_at = 0;
  std::uint32_t sent = 0;
  std::uint32_t boot_results_sent = 0;

 private:
  bool DoSend(const CanFrame& f) override {
    ++sent;
    if (FunctionOf(f.id) == static_cast<std::uint8_t>(Function::kBootResult)) {
      ++boot_results_sent;
    }
    return true;
  }
  bool DoReceive(CanFrame* f) override {
    if (in_at == in_n) return false;
    *f = in[in_at++];
    return true;
  }
  std::uint32_t DoTakeBusOff() override { return 0; }
  hal::CanPortCounters DoCounters() const override { return {}; }
};

class SpyEntry final : public hal::BootEntry {
 public:
  explicit SpyEntry(const ListPort* port) : port_(port) {}
  int calls = 0;
  std::uint32_t answers_out = 0;  // BootResults with the port when it was called

 private:
  void DoEnterBootloader() override {
    ++calls;
    answers_out = port_->boot_results_sent;
  }
  const ListPort* port_;
};

MJC_VECTOR_TEST(JointBoard, EntersItsBootloaderOnceTheHoldsAnswerIsOut) {
  static ListPort port;
  static SpyEntry entry(&port);
  JointBoardConfig config{ControlConfig{}, {}, 0, 1};
  static JointBoard board(config, &port, nullptr, &entry);
  QuietIo io;
  for (int i = 0; i < 20; ++i) {
    board.ISR_Tick(io);
    board.Poll();
  }
  VT_EXPECT_EQ(entry.calls, 0);
  port.in[port.in_n++] = Encode(BootHold{}, 1);
  board.ISR_Tick(io);
  board.Poll();
  VT_EXPECT_EQ(entry.calls, 1);
  VT_EXPECT_EQ(entry.answers_out, 1u);
}

// Encoders that turn a little every tick, so that each angle sample differs from the
// one before it.
struct TurningIo {
  Sample ISR_Read() {
    ++reads;
    Sample s;
    s.motor_count = static_cast<std::uint16_t>(3u * reads);
    s.joint_frame = EncodeJointFrame(static_cast<std::uint16_t>(reads % 16384u), false);
    return s;
  }
  void ISR_Write(const Actuation&) {}
  std::uint32_t reads = 0;
};

// A board's angle samples in the order it sent them, from either layout, and what the
// batches' counts say.
struct AngleLog {
  static constexpr std::size_t kMost = 64;
  std::int32_t motor[kMost] = {};
  std::int32_t joint[kMost] = {};
  std::size_t samples = 0;
  std::uint32_t singles = 0, batches = 0;
  std::uint32_t next_first = 0;    // the first_sample the next batch should carry
  std::uint32_t count_breaks = 0;  // batches whose first_sample was not next_first
  std::uint32_t gap_samples = 0;   // samples skipped by those
  std::uint32_t other_fd = 0;      // FD frames that are not a batch
  void Keep(Angle m, Angle j) {
    if (samples < kMost) {
      motor[samples] = m.raw();
      joint[samples] = j.raw();
    }
    ++samples;
  }
  void Take(const CanFrame& f) {
    TelemetryAngles a;
    TelemetryAngleBatch b;
    if (Decode(f, &a) == DecodeError::kOk) {
      ++singles;
      Keep(a.motor, a.joint);
    } else if (Decode(f, &b) == DecodeError::kOk) {
      if (b.first_sample != next_first) {
        ++count_breaks;
        gap_samples += b.first_sample - next_first;
      }
      next_first = b.first_sample + TelemetryAngleBatch::kSamples;
      ++batches;
      for (std::size_t i = 0; i < TelemetryAngleBatch::kSamples; ++i) {
        Keep(b.motor[i], b.joint[i]);
      }
    } else if (f.fd) {
      ++other_fd;
    }
  }
};

struct TurningBoard {
  explicit TurningBoard(bool fd)
      : app(ControlConfig{}), service(&app, nullptr), node(&service, Config(fd)) {}
  static CanNodeConfig Config(bool fd) {
    CanNodeConfig c;
    c.fd = fd;
    return c;
  }
  void Run(int ticks, bool drain = true) {
    for (int i = 0; i < ticks; ++i) {
      app.ISR_Tick(io);
      service.Poll();
      node.Poll();
      for (CanFrame f; drain && node.PopTx(&f);) log.Take(f);
    }
  }
  JointApp app;
  service::JointService service;
  CanNode node;
  TurningIo io;
  AngleLog log;
};

// On a CAN FD link the board sends its angle samples five to a TelemetryAngleBatch,
// numbered without a gap; the samples are the ones the same board sends one a frame on
// a classical link (the reference), in the same order.
MJC_VECTOR_TEST(CanNode, FdLinkBatchesTheAngleSamplesWithACount) {
  static TurningBoard classic(false);
  static TurningBoard fd(true);
  classic.Run(400);
  fd.Run(400);
  // 400 ticks at 10 kHz: 40 samples at 1 kHz, 8 batches.
  VT_EXPECT_EQ(classic.log.singles, 40u);
  VT_EXPECT_EQ(classic.log.batches, 0u);
  VT_EXPECT_EQ(fd.log.singles, 0u);
  VT_EXPECT_EQ(fd.log.batches, 8u);
  VT_EXPECT_EQ(fd.log.samples, 40u);
  VT_EXPECT_EQ(fd.log.count_breaks, 0u);
  VT_EXPECT_EQ(fd.log.next_first, 40u);
  VT_EXPECT_EQ(fd.log.other_fd, 0u);
  int differing = 0, changes = 0;
  for (std::size_t i = 0; i < 40; ++i) {
    differing += fd.log.motor[i] != classic.log.motor[i] ? 1 : 0;
    differing += fd.log.joint[i] != classic.log.joint[i] ? 1 : 0;
    if (i > 0) changes += classic.log.joint[i] != classic.log.joint[i - 1] ? 1 : 0;
  }
  VT_EXPECT_EQ(differing, 0);
  VT_EXPECT_EQ(changes, 39);  // the samples tell each other apart
}

// A batch the transmit queue had no room for is lost, and the count says so: the next
// batch that goes out starts a multiple of five samples later.
MJC_VECTOR_TEST(CanNode, ABatchLostOnTheWayOutLeavesAGapInTheCount) {
  static TurningBoard fd(true);
  fd.Run(100);
  const std::uint32_t dropped_before = fd.node.counters().tx_dropped;
  // 80 batches and the other telemetry: more than the 64 frames the queue holds.
  fd.Run(4000, /*drain=*/false);
  fd.Run(100);
  const std::uint32_t dropped = fd.node.counters().tx_dropped - dropped_before;
  VT_EXPECT_TRUE(dropped > 0);
  VT_EXPECT_EQ(fd.log.count_breaks, 1u);
  VT_EXPECT_TRUE(fd.log.gap_samples > 0);
  VT_EXPECT_EQ(fd.log.gap_samples % TelemetryAngleBatch::kSamples, 0u);
  // Every batch is either heard or among the frames the queue dropped.
  VT_EXPECT_TRUE(fd.log.gap_samples / TelemetryAngleBatch::kSamples <= dropped);
  VT_EXPECT_EQ(fd.log.batches * TelemetryAngleBatch::kSamples + fd.log.gap_samples,
               fd.log.next_first);
}

// A motion starts only with the configuration the start names: another sender's
// TrialConfig between the host's and its start makes the start a refusal, and one that
// arrives while the trial runs changes nothing of it. The board names what runs in the
// motion's first frame and in every window's start.
MJC_VECTOR_TEST(CanNode, AStartRunsOnlyTheConfigurationItNames) {
  static Board b;
  Calibrate(b);
  TrialConfig ours;
  ours.amplitude = Angle::FromDouble(0.1);
  ours.frequency_mHz = 10000;  // 10 Hz: two windows in 0.1 s
  ours.repetitions = 2;
  ours.rest_100ms = 0;
  TrialConfig foreign = ours;
  foreign.amplitude = Angle::FromDouble(0.7);
  foreign.repetitions = 5;
  const ConfigDigest digest = ConfigDigestOf(ours);
  VT_EXPECT_TRUE(digest != ConfigDigestOf(foreign));
  // Ours, then another sender's, then our start: refused, and nothing moves.
  b.node.HandleFrame(Encode(ours, 1));
  b.node.HandleFrame(Encode(foreign, 1));
  b.node.HandleFrame(Encode(Command{CommandCode::kStartTrial, 1, 0x5151, digest}, 1));
  b.Run(3);
  VT_EXPECT_EQ(b.results_n, 1);
  VT_EXPECT_TRUE(b.results[0].outcome == CommandOutcomeCode::kRefusedInvalid);
  VT_EXPECT_EQ(b.results[0].detail, kDetailConfigMismatch);
  VT_EXPECT_EQ(b.results[0].session, 0x5151);
  VT_EXPECT_TRUE(b.app.state() == BoardState::kIdle);
  VT_EXPECT_EQ(Sent<MotionConfig>(b), 0u);
  // A start naming no configuration (0, as a tool of the old protocol or cansend
  // would) is refused the same way.
  b.node.HandleFrame(Encode(Command{CommandCode::kStartTrial, 2, 0x5151}, 1));
  b.Run(1);
  VT_EXPECT_EQ(b.results[1].detail, kDetailConfigMismatch);
  // Ours again, and its start: accepted; the next frame says what runs.
  b.node.HandleFrame(Encode(ours, 1));
  b.node.HandleFrame(Encode(Command{CommandCode::kStartTrial, 3, 0x5151, digest}, 1));
  const int starts_before = b.starts_n;
  b.app.ISR_Tick(b.io);
  b.service.Poll();
  b.node.Poll();
  CanFrame f;
  bool answered = false, named = false;
  while (b.node.PopTx(&f)) {
    CommandResult r;
    MotionConfig m;
    WindowStart w;
    if (Decode(f, &w) == DecodeError::kOk && b.starts_n < 16) b.starts[b.starts_n++] = w;
    if (Decode(f, &r) == DecodeError::kOk) {
      answered = r.outcome == CommandOutcomeCode::kAccepted && r.sequence == 3 &&
                 r.session == 0x5151 && r.owner == 0x5151;
    } else if (Decode(f, &m) == DecodeError::kOk) {
      named = answered && m.start == CommandCode::kStartTrial && m.session == 0x5151 &&
              m.config == digest;
    }
  }
  VT_EXPECT_TRUE(answered);
  VT_EXPECT_TRUE(named);
  VT_EXPECT_TRUE(b.app.state() == BoardState::kRunning);
  // Another sender's configuration mid-trial, and another session's start: the trial
  // runs as started, and the refusal names who holds the board.
  b.node.HandleFrame(Encode(foreign, 1));
  b.node.HandleFrame(
      Encode(Command{CommandCode::kStartTrial, 9, 0x7272, ConfigDigestOf(foreign)}, 1));
  b.Drain();
  const CommandResult busy = Last<CommandResult>(vt_context, b);
  VT_EXPECT_TRUE(busy.outcome == CommandOutcomeCode::kRefusedNotIdle);
  VT_EXPECT_EQ(busy.session, 0x7272);
  VT_EXPECT_EQ(busy.owner, 0x5151);
  VT_EXPECT_EQ(busy.detail, static_cast<std::uint8_t>(CommandCode::kStartTrial));
  double widest = 0;
  for (int i = 0; i < 3000 && b.app.state() == BoardState::kRunning; ++i) {
    b.Run(1);
    const double setpoint = b.app.Latest().telemetry.setpoint.ToDouble();
    widest = std::max(widest, setpoint < 0 ? -setpoint : setpoint);
  }
  VT_EXPECT_TRUE(b.app.state() == BoardState::kIdle);
  // Our two repetitions (four windows) at our amplitude, each window named ours.
  VT_EXPECT_EQ(b.starts_n - starts_before, 4);
  for (int i = starts_before; i < b.starts_n; ++i) {
    VT_EXPECT_EQ(b.starts[i].config16, digest & 0xFFFFu);
  }
  VT_EXPECT_TRUE(widest > 0.09 && widest < 0.11);
}

// The calibration sweep is bound the same way.
MJC_VECTOR_TEST(CanNode, ASweepRunsOnlyTheConfigurationItNames) {
  static Board b;
  SweepConfig ours;
  ours.end_amplitude = Angle::FromDouble(0.3);
  SweepConfig foreign = ours;
  foreign.repetitions = 40;
  b.node.HandleFrame(Encode(ours, 1));
  b.node.HandleFrame(Encode(foreign, 1));
  b.node.HandleFrame(
      Encode(Command{CommandCode::kStartSweep, 1, 0x0101, ConfigDigestOf(ours)}, 1));
  b.Run(2);
  VT_EXPECT_TRUE(Last<CommandResult>(vt_context, b).outcome ==
                 CommandOutcomeCode::kRefusedInvalid);
  VT_EXPECT_TRUE(b.app.state() == BoardState::kIdle);
  b.node.HandleFrame(Encode(ours, 1));
  b.node.HandleFrame(
      Encode(Command{CommandCode::kStartSweep, 2, 0x0101, ConfigDigestOf(ours)}, 1));
  b.Run(2);
  VT_EXPECT_TRUE(Last<CommandResult>(vt_context, b).outcome ==
                 CommandOutcomeCode::kAccepted);
  VT_EXPECT_TRUE(b.app.state() == BoardState::kCalibrating);
  const MotionConfig m = Last<MotionConfig>(vt_context, b);
  VT_EXPECT_TRUE(m.start == CommandCode::kStartSweep && m.session == 0x0101 &&
                 m.config == ConfigDigestOf(ours));
}

}  // namespace
