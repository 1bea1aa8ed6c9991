// mjc param's library against the simulated board (the firmware's application and CAN
// node on the plant, ticking in a thread of its own) over an in-process bus: a dump's
// values are the board's defaults, a restore brings back what a set changed — read
// from the board's own fields afterwards — a motion makes the board refuse control
// parameters, so a restore refuses before it sends anything, and the board's own check
// of its configuration is reported with the parameter's rule. Every wait is on the
// board's answers and its clock (BoardClient::Await), none on this machine's.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <thread>
#include <vector>

#include "mjc/app/joint_config.h"
#include "mjc/host/param_io.h"
#include "mjc/plant/params.h"
#include "mjc/sim/link_can_port.h"
#include "mjc/sim/sim_board.h"

namespace {

using namespace mjc;
using host::ParamWriteEnd;
using protocol::ParamStatus;

constexpr std::uint8_t kNode = 3;
constexpr int kTimeoutMs = 1000;

app::JointBoardConfig BoardConfig() {
  app::JointBoardConfig config{app::DefaultJointConfig(), {}, 0, 1};
  config.can.node = kNode;
  return config;
}

class ParamsOnTheBus : public ::testing::Test {
 protected:
  void SetUp() override {
    // Only the parameter writes: what a refused restore must not have sent.
    const host::IdFilter writes{
        protocol::MakeId(static_cast<std::uint8_t>(protocol::Function::kParamWrite),
                         kNode),
        0x7FF};
    ASSERT_TRUE(sniffer_->SetFilters({&writes, 1}, &why_)) << why_;
    thread_ = std::thread([this] {
      while (!stop_) {
        board_.Tick();
        board_.Poll();
      }
    });
    host::WaitEnd end{};
    ASSERT_TRUE(client_.Identify(&end, &why_)) << why_;
    ASSERT_EQ(host::CheckProtocolVersion(client_, kTimeoutMs, &why_),
              host::ProtocolCheck::kSame)
        << why_;
  }
  void TearDown() override { StopBoard(); }
  // After this, the board's fields may be read here.
  void StopBoard() {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
  }

  host::ParamSetting Set(const char* assignment) {
    const auto s = host::ParseParamAssignment(assignment, &why_);
    EXPECT_TRUE(s) << assignment << ": " << why_;
    return s.value_or(host::ParamSetting{});
  }
  nlohmann::json Dump() {
    const auto all = host::AllParams();
    const auto readings = host::ReadParams(client_, all, kTimeoutMs, &why_);
    EXPECT_TRUE(readings) << why_;
    if (!readings) return {};
    return nlohmann::json::parse(
        host::ParamDumpToJson(kNode, client_.info(), *readings, "now").dump());
  }
  std::vector<host::ParamSetting> Restorable(const nlohmann::json& dump) {
    const auto settings = host::ParamRestoreFromJson(dump, &why_);
    EXPECT_TRUE(settings) << why_;
    return settings.value_or(std::vector<host::ParamSetting>{});
  }
  // Waits, at the board's pace, until its heartbeat reports `state`.
  void AwaitState(protocol::BoardState state) {
    host::WaitEnd end{};
    ASSERT_TRUE(client_.Await([&] { return client_.status().state == state; },
                              {std::chrono::seconds(5)}, &end, &why_))
        << why_;
  }
  // The parameter writes the bus has carried so far.
  int WritesSent() {
    int n = 0;
    for (auto r = sniffer_->Receive(0, &why_); r; r = sniffer_->Receive(0, &why_)) ++n;
    return n;
  }

  std::shared_ptr<host::InProcessBus> bus_ = host::InProcessBus::Create();
  std::unique_ptr<host::CanLink> board_link_ = bus_->Connect();
  std::unique_ptr<host::CanLink> host_link_ = bus_->Connect();
  std::unique_ptr<host::CanLink> sniffer_ = bus_->Connect();
  sim::LinkCanPort port_{board_link_.get()};
  sim::SimBoard board_{plant::LoadPlantParams("default"), BoardConfig(), &port_};
  host::BoardClient client_{host_link_.get(), kNode};
  std::atomic<bool> stop_{false};
  std::thread thread_;
  std::string why_;
};

TEST_F(ParamsOnTheBus, ARestoreBringsBackWhatASetChanged) {
  const app::JointBoardConfig defaults = BoardConfig();
  const nlohmann::json dump = Dump();
  // The dump holds the board's values: its configuration's, in the list's units.
  EXPECT_EQ(dump["node"], kNode);
  EXPECT_EQ(dump["params"]["heartbeat_hz"], defaults.can.rates.heartbeat_hz);
  EXPECT_EQ(dump["params"]["position_kp"], defaults.control.position.kp.ToDouble());
  EXPECT_EQ(dump["params"]["torque_max"],
            defaults.control.supervisor.torque_max.ToDouble());
  EXPECT_EQ(dump["read_only"]["calibrated"], 0);
  EXPECT_EQ(dump["read_only"]["protocol_version"], protocol::kVersion);

  const std::vector<host::ParamSetting> changes = {
      Set("telemetry_torque_hz=20"), Set("position_kp=0.1"), Set("velocity_window=301")};
  host::ParamWriteOutcome set = host::WriteParams(client_, changes, kTimeoutMs);
  ASSERT_EQ(set.end, ParamWriteEnd::kDone) << set.why;
  EXPECT_EQ(set.written, 3u);
  const auto kp = client_.ReadParam(protocol::ParamId::kPositionKp, kTimeoutMs, &why_);
  ASSERT_TRUE(kp) << why_;
  EXPECT_EQ(*kp, 6554);

  const auto settings = Restorable(dump);
  const host::ParamWriteOutcome restored =
      host::RestoreParams(client_, settings, kTimeoutMs);
  ASSERT_EQ(restored.end, ParamWriteEnd::kDone) << restored.why;
  EXPECT_EQ(restored.written, 3u);
  EXPECT_EQ(restored.unchanged, settings.size() - 3);

  // The board's own fields, against the configuration it started with.
  StopBoard();
  const app::CanNodeConfig& node = board_.board().node().config();
  EXPECT_EQ(node.rates.torque_hz, defaults.can.rates.torque_hz);
  const ControlConfig& control = board_.app().control().config();
  EXPECT_EQ(control.position.kp, defaults.control.position.kp);
  EXPECT_EQ(control.velocity_window, defaults.control.velocity_window);
}

TEST_F(ParamsOnTheBus, AMotionRefusesControlParametersAndARestoreSendsNothing) {
  const nlohmann::json dump = Dump();
  // A calibration sweep far longer than this test (255 cycles at 0.1 Hz).
  protocol::SweepConfig sweep;
  sweep.end_amplitude = Angle::Quantize(0.05);
  sweep.frequency_mHz = 100;
  sweep.repetitions = 255;
  sweep.rest_100ms = 0;
  const auto started = client_.Start(sweep, host::kStartAnswerMs, &why_);
  ASSERT_TRUE(started) << why_;
  ASSERT_EQ(*started, protocol::CommandOutcomeCode::kAccepted);
  AwaitState(protocol::BoardState::kCalibrating);
  ASSERT_EQ(WritesSent(), 0);

  const host::ParamWriteOutcome restore =
      host::RestoreParams(client_, Restorable(dump), kTimeoutMs);
  EXPECT_EQ(restore.end, ParamWriteEnd::kNotIdle);
  EXPECT_EQ(restore.why,
            "node 3 is calibrating (a calibration sweep): the board takes control "
            "parameters and protections only while idle; nothing was sent");
  EXPECT_EQ(WritesSent(), 0);

  // One write: the board's own refusal, with its reason.
  const std::vector<host::ParamSetting> kp = {Set("position_kp=1")};
  const host::ParamWriteOutcome set = host::WriteParams(client_, kp, kTimeoutMs);
  EXPECT_EQ(set.end, ParamWriteEnd::kRefused);
  EXPECT_EQ(set.status, ParamStatus::kRefusedNotIdle);
  EXPECT_EQ(set.why,
            "node 3 refused position_kp = 1: a motion runs (the protections and the "
            "control parameters change only while the board is idle)");
  EXPECT_EQ(WritesSent(), 1);

  // A protection of the node's own (a timeout) stays as the motion started under it.
  const std::vector<host::ParamSetting> timeout = {Set("host_timeout_ms=500")};
  const host::ParamWriteOutcome guard = host::WriteParams(client_, timeout, kTimeoutMs);
  EXPECT_EQ(guard.end, ParamWriteEnd::kRefused);
  EXPECT_EQ(guard.status, ParamStatus::kRefusedNotIdle);

  // The telemetry rates apply at once, sweep or not: a restore of those alone runs.
  nlohmann::json rates = {{"protocol_version", protocol::kVersion},
                          {"params", {{"telemetry_torque_hz", 20}}}};
  const host::ParamWriteOutcome node =
      host::RestoreParams(client_, Restorable(rates), kTimeoutMs);
  EXPECT_EQ(node.end, ParamWriteEnd::kDone) << node.why;
  EXPECT_EQ(node.written, 1u);

  const auto stopped = client_.Command(protocol::CommandCode::kStop, kTimeoutMs, &why_);
  ASSERT_TRUE(stopped) << why_;
  AwaitState(protocol::BoardState::kIdle);
  const host::ParamWriteOutcome idle = host::WriteParams(client_, kp, kTimeoutMs);
  EXPECT_EQ(idle.end, ParamWriteEnd::kDone) << idle.why;
}

// A dump of each writable parameter at each end of its range goes through mjc param
// restore's path (the file's checks, then RestoreParams against the board): an end is
// taken and read back, unless the board's check of its whole configuration refuses it
// (kOutOfRange, the old value kept). One step beyond either end the file is refused
// before anything is sent, and, the host's check bypassed, the board refuses it too,
// naming the bound, and keeps what it held. A joint limit, once tightened, refuses its
// loose end as beyond the joint's limit.
TEST_F(ParamsOnTheBus, ARestoreOfEveryParametersExtremesKeepsEveryProtectionOn) {
  const auto read = [&](const protocol::ParamInfo& info) {
    const auto v = client_.ReadParam(info.id, kTimeoutMs, &why_);
    EXPECT_TRUE(v) << info.key << ": " << why_;
    return v.value_or(0);
  };
  // A dump holding `raw` for `info` alone, as mjc param dump writes the value.
  const auto dump_of = [&](const protocol::ParamInfo& info, std::int64_t raw) {
    nlohmann::json dump = {{"protocol_version", protocol::kVersion},
                           {"params", nlohmann::json::object()}};
    if (info.frac_bits == 0) {
      dump["params"][info.key] = raw;
    } else {
      dump["params"][info.key] = std::ldexp(static_cast<double>(raw), -info.frac_bits);
    }
    return dump;
  };
  const auto restore = [&](const protocol::ParamInfo& info, std::int64_t raw) {
    const auto settings = host::ParamRestoreFromJson(dump_of(info, raw), &why_);
    EXPECT_TRUE(settings) << info.key << " = " << raw << ": " << why_;
    if (!settings) {
      host::ParamWriteOutcome none;
      none.end = ParamWriteEnd::kNoAnswer;
      return none;
    }
    return host::RestoreParams(client_, *settings, kTimeoutMs);
  };
  int taken = 0, refused_whole = 0, refused_beyond = 0;
  for (const protocol::ParamInfo& info : protocol::kParams) {
    if (info.access == protocol::ParamAccess::kReadOnly) continue;
    const std::int32_t held = read(info);
    const bool joint_limit = info.access == protocol::ParamAccess::kJointLimit;
    const bool lower_is_loose = info.id == protocol::ParamId::kJointAngleMin;
    const std::int64_t loose = lower_is_loose ? info.min_raw : info.max_raw;
    // A supervisor limit at its tight end (1 raw step) latches its fault on a board at
    // rest, whose sensors are not that still; the board-side vectors take those ends
    // (param_bounds_vectors.cc). Here it is tightened to half its loose end.
    const bool supervisor_limit = joint_limit ||
                                  info.id == protocol::ParamId::kTorqueMax ||
                                  info.id == protocol::ParamId::kVelocityMax;
    const std::int64_t tight = supervisor_limit ? loose / 2
                               : lower_is_loose ? info.max_raw
                                                : info.min_raw;
    // Beyond either end: the file is refused by the host...
    for (const std::int64_t beyond : {info.min_raw - 1, info.max_raw + 1}) {
      if (beyond < INT32_MIN || beyond > INT32_MAX) continue;  // not on the wire
      std::string refused;
      EXPECT_FALSE(host::ParamRestoreFromJson(dump_of(info, beyond), &refused))
          << info.key;
      EXPECT_NE(refused.find(" is outside "), std::string::npos) << refused;
      // ...and by the board, when a host does not check.
      host::ParamSetting raw{&info, static_cast<std::int32_t>(beyond), 0, true};
      const host::ParamWriteOutcome o =
          host::RestoreParams(client_, {&raw, 1}, kTimeoutMs);
      EXPECT_EQ(o.end, ParamWriteEnd::kRefused)
          << info.key << " = " << beyond << ": " << o.why;
      const std::int64_t bound = beyond < info.min_raw ? info.min_raw : info.max_raw;
      EXPECT_EQ(o.status, beyond < info.min_raw ? ParamStatus::kBelowMinimum
                                                : ParamStatus::kAboveMaximum)
          << info.key;
      EXPECT_NE(o.why.find(": " + host::FormatParamWithUnit(
                                      info, static_cast<std::int32_t>(bound))),
                std::string::npos)
          << o.why;
      EXPECT_EQ(read(info), held) << info.key;
      ++refused_beyond;
    }
    // Each end.
    for (const std::int64_t end : {tight, loose}) {
      const host::ParamWriteOutcome o = restore(info, end);
      if (o.end == ParamWriteEnd::kDone) {
        EXPECT_EQ(read(info), end) << info.key;
        ++taken;
      } else if (joint_limit && end == loose) {
        // The tight end was taken: the loose one is beyond the joint's limit now.
        EXPECT_EQ(o.end, ParamWriteEnd::kRefused) << o.why;
        EXPECT_EQ(o.status, ParamStatus::kBeyondJointLimit) << o.why;
        EXPECT_EQ(read(info), tight) << info.key;
        ++refused_beyond;
      } else {
        EXPECT_EQ(o.end, ParamWriteEnd::kRefused)
            << info.key << " = " << end << ": " << o.why;
        EXPECT_EQ(o.status, ParamStatus::kOutOfRange) << info.key << ": " << o.why;
        EXPECT_EQ(read(info), held) << info.key;
        ++refused_whole;
      }
    }
    if (!joint_limit) {
      const host::ParamWriteOutcome back = restore(info, held);
      EXPECT_EQ(back.end, ParamWriteEnd::kDone) << info.key << ": " << back.why;
    }
  }
  // What the walk saw, so that a walk that skipped everything fails.
  EXPECT_GE(taken, 30);
  EXPECT_GE(refused_beyond, 40);
  EXPECT_LE(refused_whole, 4);
  std::printf(
      "extremes taken %d, refused by the whole-configuration check %d, refused "
      "beyond a bound %d\n",
      taken, refused_whole, refused_beyond);
}

TEST_F(ParamsOnTheBus, TheBoardsCheckOfItsConfigurationNamesTheRule) {
  // Within the list's range (33..1001), but the estimator's window must be odd.
  const std::vector<host::ParamSetting> even = {
      Set("heartbeat_hz=20"), Set("velocity_window=34"), Set("torque_max=1")};
  const host::ParamWriteOutcome set = host::WriteParams(client_, even, kTimeoutMs);
  EXPECT_EQ(set.end, ParamWriteEnd::kRefused);
  EXPECT_EQ(set.status, ParamStatus::kOutOfRange);
  EXPECT_EQ(set.written, 1u);
  EXPECT_EQ(
      set.why,
      "node 3 refused velocity_window = 34: out of range, or refused by the board's "
      "check of its whole control configuration (joint velocity estimator's window "
      "(odd; its delay aligns the torque))");
  StopBoard();
  EXPECT_EQ(board_.app().control().config().velocity_window,
            BoardConfig().control.velocity_window);
  EXPECT_EQ(board_.board().node().config().rates.heartbeat_hz, 20);
}

}  // namespace
