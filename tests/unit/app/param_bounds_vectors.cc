// The protections' parameters on the board's side: a write beyond a bound is refused
// with the bound in the answer and the old value kept; every one of them is refused
// while a motion runs; the joint's limits only tighten, and torque_max stays within
// the joint's torque limit. The bounds below are written from the reasons the
// parameter list gives (protocol/params.h), as numbers, not read from the list: a
// list loosened by mistake fails here.
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

struct Board {
  Board()
      : app(ControlConfig{}), service(&app, nullptr), node(&service, CanNodeConfig{}) {}
  void Run(int ticks) {
    for (int i = 0; i < ticks; ++i) {
      app.ISR_Tick(io);
      service.Poll();
      node.Poll();
      Drain();
    }
  }
  void Drain() {
    CanFrame f;
    while (node.PopTx(&f)) {
      ParamValue v;
      if (Decode(f, &v) == DecodeError::kOk) {
        last = v;
        ++answers;
      }
    }
  }
  // A write and the board's answer (a control parameter's after the tick's verdict).
  ParamValue Write(ParamId id, std::int32_t raw) {
    const std::uint32_t before = answers;
    node.HandleFrame(Encode(ParamWrite{id, raw}, 1));
    Drain();
    if (answers == before) Run(2);
    return last;
  }
  std::int32_t Read(ParamId id) {
    node.HandleFrame(Encode(ParamRead{id}, 1));
    Drain();
    return last.value;
  }
  JointApp app;
  service::JointService service;
  CanNode node;
  QuietIo io;
  ParamValue last;
  std::uint32_t answers = 0;
};

struct Bounds {
  ParamId id;
  std::int32_t min;
  std::int32_t max;
};

// Q7.24 torque and angle, Q11.20 velocity, Q15.16 gains.
constexpr std::int32_t kNm = 1 << 24;
constexpr std::int32_t kRad = 1 << 24;
constexpr std::int32_t kRadPerS = 1 << 20;
constexpr std::int32_t kGain = 1 << 16;
constexpr std::int32_t k1p6Rad = 26843546;  // 1.6 · 2^24 = 26843545.6, to nearest

constexpr Bounds kProtections[] = {
    {ParamId::kHeartbeatHz, 10, 1000},       // the tools' 100 ms; a tenth of a bus
    {ParamId::kStreamTimeoutMs, 1, 100},     // the 100 ms goal for lost commands
    {ParamId::kHostTimeoutMs, 200, 1000},    // two host heartbeats; 1 s orphaned
    {ParamId::kPositionKp, 0, 400 * kGain},  // ten times the tuned gains
    {ParamId::kPositionKi, 0, 2000 * kGain},  {ParamId::kPositionKd, 0, kGain / 2},
    {ParamId::kPositionKff, 0, 62259},          // 0.95 · 2^16 = 62259.2
    {ParamId::kTorqueMax, 1, 5 * kNm},          // the image's 5 N·m ceiling
    {ParamId::kJointTorqueLimit, 1, 5 * kNm},   //
    {ParamId::kJointAngleMin, -k1p6Rad, -1},    // the board's ±1.6 rad
    {ParamId::kJointAngleMax, 1, k1p6Rad},      //
    {ParamId::kVelocityMax, 1, 5 * kRadPerS}};  // the supervisor's 5 rad/s

MJC_VECTOR_TEST(ParamBounds, EveryProtectionRefusesWritesBeyondItsBoundsNamingThem) {
  static Board b;
  b.Run(1);
  for (const Bounds& p : kProtections) {
    const std::int32_t held = b.Read(p.id);
    ParamValue v = b.Write(p.id, p.min - 1);
    VT_EXPECT_TRUE(v.id == p.id && v.status == ParamStatus::kBelowMinimum);
    VT_EXPECT_EQ(v.value, p.min);
    VT_EXPECT_EQ(b.Read(p.id), held);
    v = b.Write(p.id, p.max + 1);
    VT_EXPECT_TRUE(v.id == p.id && v.status == ParamStatus::kAboveMaximum);
    VT_EXPECT_EQ(v.value, p.max);
    VT_EXPECT_EQ(b.Read(p.id), held);
    // Far beyond (the values that switched a protection off before) the same way.
    v = b.Write(p.id, p.max > 0 ? 0x7FFFFFFF : -0x7FFFFFFF - 1);
    VT_EXPECT_TRUE(v.status ==
                   (p.max > 0 ? ParamStatus::kAboveMaximum : ParamStatus::kBelowMinimum));
    VT_EXPECT_EQ(b.Read(p.id), held);
  }
}

MJC_VECTOR_TEST(ParamBounds, EachBoundItselfIsTaken) {
  static Board b;
  b.Run(1);
  for (const Bounds& p : kProtections) {
    const std::int32_t held = b.Read(p.id);
    // A joint limit only tightens: its loose end is what it holds from the reset.
    const ParamInfo* info = FindParam(p.id);
    const bool joint_limit = info != nullptr && info->access == ParamAccess::kJointLimit;
    const std::int32_t loose = p.id == ParamId::kJointAngleMin ? p.min : p.max;
    const std::int32_t tight = p.id == ParamId::kJointAngleMin ? p.max : p.min;
    if (joint_limit) {
      VT_EXPECT_EQ(held, loose);
      VT_EXPECT_TRUE(b.Write(p.id, loose).status == ParamStatus::kOk);
      continue;  // the tight end: ParamBounds.TheJointsLimitsOnlyTighten
    }
    VT_EXPECT_TRUE(b.Write(p.id, tight).status == ParamStatus::kOk);
    VT_EXPECT_EQ(b.Read(p.id), tight);
    VT_EXPECT_TRUE(b.Write(p.id, loose).status == ParamStatus::kOk);
    VT_EXPECT_EQ(b.Read(p.id), loose);
    VT_EXPECT_TRUE(b.Write(p.id, held).status == ParamStatus::kOk);
  }
}

MJC_VECTOR_TEST(ParamBounds, NoProtectionChangesWhileAMotionRuns) {
  static Board b;
  mjc::Calibration c;
  c.backlash.c_right = Angle::FromDouble(0.0175);
  c.backlash.c_left = Angle::FromDouble(-0.0175);
  b.app.SetCalibration(c);
  b.Run(1);
  TrialConfig t;
  t.amplitude = Angle::FromDouble(0.2);
  b.node.HandleFrame(Encode(t, 1));
  b.node.HandleFrame(
      Encode(Command{CommandCode::kStartTrial, 1, 0, ConfigDigestOf(t)}, 1));
  b.Run(2);
  VT_EXPECT_TRUE(b.app.state() == BoardState::kRunning);
  for (const Bounds& p : kProtections) {
    const std::int32_t held = b.Read(p.id);
    // Within the range and tighter than what is held: refused only for the motion.
    const std::int32_t tighter = p.id == ParamId::kJointAngleMin ? p.max : p.min;
    const ParamValue v = b.Write(p.id, tighter);
    VT_EXPECT_TRUE(v.id == p.id && v.status == ParamStatus::kRefusedNotIdle);
    VT_EXPECT_EQ(b.Read(p.id), held);
  }
  // A telemetry rate protects nothing: it may change mid-motion.
  VT_EXPECT_TRUE(b.Write(ParamId::kTelemetryTorqueHz, 20).status == ParamStatus::kOk);
  VT_EXPECT_TRUE(b.app.state() == BoardState::kRunning);
}

MJC_VECTOR_TEST(ParamBounds, TheJointsLimitsOnlyTighten) {
  static Board b;
  b.Run(1);
  VT_EXPECT_EQ(b.Read(ParamId::kTorqueMax), 1 * kNm);  // the image's default
  // The description's torque limit below torque_max brings torque_max down with it.
  VT_EXPECT_TRUE(b.Write(ParamId::kJointTorqueLimit, kNm / 2).status == ParamStatus::kOk);
  VT_EXPECT_EQ(b.Read(ParamId::kJointTorqueLimit), kNm / 2);
  VT_EXPECT_EQ(b.Read(ParamId::kTorqueMax), kNm / 2);
  VT_EXPECT_EQ(b.app.control().config().supervisor.torque_max.raw(), kNm / 2);
  // torque_max beyond it: refused, naming the joint's limit.
  ParamValue v = b.Write(ParamId::kTorqueMax, kNm);
  VT_EXPECT_TRUE(v.status == ParamStatus::kBeyondJointLimit);
  VT_EXPECT_EQ(v.value, kNm / 2);
  VT_EXPECT_EQ(b.Read(ParamId::kTorqueMax), kNm / 2);
  // Within it, either way.
  VT_EXPECT_TRUE(b.Write(ParamId::kTorqueMax, kNm / 4).status == ParamStatus::kOk);
  VT_EXPECT_TRUE(b.Write(ParamId::kTorqueMax, kNm / 2).status == ParamStatus::kOk);
  // The limit itself never loosens.
  v = b.Write(ParamId::kJointTorqueLimit, kNm);
  VT_EXPECT_TRUE(v.status == ParamStatus::kBeyondJointLimit);
  VT_EXPECT_EQ(v.value, kNm / 2);
  VT_EXPECT_EQ(b.Read(ParamId::kJointTorqueLimit), kNm / 2);
  // A torque limit above torque_max leaves torque_max alone.
  VT_EXPECT_TRUE(b.Write(ParamId::kTorqueMax, kNm / 4).status == ParamStatus::kOk);
  VT_EXPECT_TRUE(b.Write(ParamId::kJointTorqueLimit, kNm * 3 / 8).status ==
                 ParamStatus::kOk);
  VT_EXPECT_EQ(b.Read(ParamId::kTorqueMax), kNm / 4);
  // The travel: tightened, then not loosened, on either side.
  VT_EXPECT_TRUE(b.Write(ParamId::kJointAngleMax, kRad).status == ParamStatus::kOk);
  VT_EXPECT_EQ(b.app.control().config().supervisor.joint_max.raw(), kRad);
  v = b.Write(ParamId::kJointAngleMax, kRad + 1);
  VT_EXPECT_TRUE(v.status == ParamStatus::kBeyondJointLimit);
  VT_EXPECT_EQ(v.value, kRad);
  VT_EXPECT_TRUE(b.Write(ParamId::kJointAngleMin, -kRad / 2).status == ParamStatus::kOk);
  VT_EXPECT_EQ(b.app.control().config().supervisor.joint_min.raw(), -kRad / 2);
  v = b.Write(ParamId::kJointAngleMin, -kRad / 2 - 1);
  VT_EXPECT_TRUE(v.status == ParamStatus::kBeyondJointLimit);
  VT_EXPECT_EQ(v.value, -kRad / 2);
  VT_EXPECT_EQ(b.Read(ParamId::kJointAngleMin), -kRad / 2);
  // The same value again is no loosening (a tool sends the description each time).
  VT_EXPECT_TRUE(b.Write(ParamId::kJointAngleMax, kRad).status == ParamStatus::kOk);
}

}  // namespace
