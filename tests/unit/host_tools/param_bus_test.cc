// mjc param's library against the simulated board (the firmware's application and CAN
// node on the plant, ticking in a thread of its own) over an in-process bus: a dump's
// values are the board's defaults, a restore brings back what a set changed — read
// from the board's own fields afterwards — a motion makes the board refuse control
// parameters, so a restore refuses before it sends anything, and the board's own check
// of its configuration is reported with the parameter's rule. Every wait is on the
// board's answers and its clock (BoardClient::Await), none on this machine's.
#include <gtest/gtest.h>

#include <atomic>
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
            "parameters only while idle; nothing was sent");
  EXPECT_EQ(WritesSent(), 0);

  // One write: the board's own refusal, with its reason.
  const std::vector<host::ParamSetting> kp = {Set("position_kp=1")};
  const host::ParamWriteOutcome set = host::WriteParams(client_, kp, kTimeoutMs);
  EXPECT_EQ(set.end, ParamWriteEnd::kRefused);
  EXPECT_EQ(set.status, ParamStatus::kRefusedNotIdle);
  EXPECT_EQ(set.why,
            "node 3 refused position_kp = 1: the board is not idle (control parameters "
            "change only while it is)");
  EXPECT_EQ(WritesSent(), 1);

  // The node's own settings apply at once, sweep or not: a restore of those alone runs.
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
