// A trial whose configuration another sender contests, over the in-process bus (the
// simulated board on the plant, the host's BoardClient and mjc trial's runner). A
// configuration frame carries no sender, so the board cannot tell whose it holds: the
// start names the host's configuration (its digest), and what runs is named back in the
// motion's first frame and every window's start.
//
// - Another sender's TrialConfig between the host's and its start: the board refuses
//   the start, the host sends the pair again, and the trial that runs is the host's —
//   the plant's joint swings the host's amplitude, and its windows are recorded.
// - Another sender's TrialConfig between every pair: the trial is refused with the
//   reason, and nothing moves.
// - A board that ran another configuration than the one the host sent (the host's
//   frames replaced on the way): the host sees it in the motion's first frame, stops
//   it, and records no window; the message names both configurations.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <numbers>
#include <string>

#include "mjc/app/joint_config.h"
#include "mjc/host/board_client.h"
#include "mjc/host/trial_runner.h"
#include "mjc/plant/params.h"
#include "mjc/protocol/codec.h"
#include "mjc/sim/bus_board.h"

namespace {

using namespace mjc;
using namespace mjc::protocol;

constexpr double kDeg = std::numbers::pi / 180.0;

// The host's link, with another sender beside it on the bus: after the host's
// TrialConfig (kInterleave) the other sender's follows at once, before the host's start;
// or (kReplace) the host's configuration and its start's digest are replaced by the
// other's on the way, as if the board had taken another configuration for the host's.
class ContestedLink final : public host::CanLink {
 public:
  enum class Mode { kInterleave, kReplace };
  ContestedLink(std::unique_ptr<host::CanLink> host, std::unique_ptr<host::CanLink> other,
                const TrialConfig& foreign, Mode mode, int times)
      : host_(std::move(host)),
        other_(std::move(other)),
        foreign_(foreign),
        mode_(mode),
        times_(times) {}
  int contested() const { return contested_; }

 private:
  bool DoSend(const CanFrame& frame, std::string* why) override {
    const auto function = static_cast<Function>(FunctionOf(frame.id));
    if (mode_ == Mode::kReplace && times_ > 0) {
      if (function == Function::kTrialConfig) {
        return host_->Send(Encode(foreign_, NodeOf(frame.id)), why);
      }
      Command c;
      if (Decode(frame, &c) == DecodeError::kOk && c.code == CommandCode::kStartTrial) {
        --times_;
        ++contested_;
        c.config = ConfigDigestOf(foreign_);
        return host_->Send(Encode(c, NodeOf(frame.id)), why);
      }
    }
    if (!host_->Send(frame, why)) return false;
    if (mode_ == Mode::kInterleave && function == Function::kTrialConfig && times_ > 0) {
      --times_;
      ++contested_;
      return other_->Send(Encode(foreign_, NodeOf(frame.id)), why);
    }
    return true;
  }
  host::ReceiveResult DoReceive(int timeout_ms, std::string* why) override {
    return host_->Receive(timeout_ms, why);
  }
  bool DoSetFilters(std::span<const host::IdFilter> filters, std::string* why) override {
    return host_->SetFilters(filters, why);
  }

  std::unique_ptr<host::CanLink> host_;
  std::unique_ptr<host::CanLink> other_;
  TrialConfig foreign_;
  Mode mode_;
  int times_;
  int contested_ = 0;
};

TrialConfig Ours() {
  TrialConfig c;
  c.amplitude = Angle::Quantize(6.0 * kDeg);
  c.frequency_mHz = 1000;
  c.repetitions = 3;
  c.rest_100ms = 2;
  return c;
}

TrialConfig Foreign() {
  TrialConfig c;
  c.amplitude = Angle::Quantize(40.0 * kDeg);
  c.frequency_mHz = 1000;
  c.repetitions = 5;
  c.rest_100ms = 2;
  return c;
}

struct Outcome {
  host::BoardTrial trial;
  double widest_setpoint_rad = 0;  // how far the board's trajectory took the joint
  int contested = 0;
  app::BoardState final_state = app::BoardState::kIdle;
  std::uint64_t unbound_windows = 0;
};

Outcome RunContested(ContestedLink::Mode mode, int times) {
  plant::PlantParams params = plant::LoadPlantParams("default");
  params.interface = plant::LoadPlantParams("subject1").interface;
  sim::BusBoard bus(params, app::DefaultJointConfig());
  Calibration cal;
  cal.backlash.c_right = Angle::Quantize(params.cable.c_right_rad);
  cal.backlash.c_left = Angle::Quantize(params.cable.c_left_rad);
  bus.app().SetCalibration(cal);
  bus.Run(1);
  Outcome out;
  bus.SetAfterTick([&](sim::SimBoard& board) {
    out.widest_setpoint_rad =
        std::max(out.widest_setpoint_rad,
                 std::fabs(board.app().last().telemetry.setpoint.ToDouble()));
  });
  ContestedLink link(bus.Connect(), bus.Connect(), Foreign(), mode, times);
  host::BoardClient client(&link, bus.node(), host::HostHeartbeats::kSend, bus.Clock());
  out.trial = host::RunBoardTrial(client, Ours(), {});
  if (out.trial.end == host::TrialEnd::kWrongConfig) {
    // What mjc trial does: the motion that is not its own is stopped.
    std::string why;
    EXPECT_EQ(client.Command(CommandCode::kStop, 1000, &why),
              CommandOutcomeCode::kAccepted)
        << why;
  }
  bus.Run(1000);
  bus.SetAfterTick(nullptr);
  out.contested = link.contested();
  out.final_state = bus.app().state();
  out.unbound_windows = client.unbound_windows();
  return out;
}

TEST(BusTrialForeignConfig, ConfigurationBetweenOursAndTheStartIsRefusedThenOursRuns) {
  const Outcome out = RunContested(ContestedLink::Mode::kInterleave, 1);
  EXPECT_EQ(out.contested, 1);
  ASSERT_TRUE(out.trial.completed) << out.trial.error;
  EXPECT_EQ(out.trial.windows.size(), 6u);  // three repetitions, ours
  // The board's trajectory swung our 6°, not the other's 40°.
  EXPECT_NEAR(out.widest_setpoint_rad, 6.0 * kDeg, 0.1 * kDeg);
}

TEST(BusTrialForeignConfig, AlwaysContestedIsRefusedWithTheReasonAndNothingMoves) {
  const Outcome out = RunContested(ContestedLink::Mode::kInterleave, 100);
  EXPECT_EQ(out.contested, 3);  // the pair sent three times
  EXPECT_EQ(out.trial.end, host::TrialEnd::kRefused);
  EXPECT_NE(out.trial.error.find("holds another configuration"), std::string::npos)
      << out.trial.error;
  EXPECT_NE(out.trial.error.find("6.0° × 3"), std::string::npos) << out.trial.error;
  EXPECT_TRUE(out.trial.windows.empty());
  EXPECT_EQ(out.widest_setpoint_rad, 0.0);
}

TEST(BusTrialForeignConfig, ABoardRunningAnotherConfigurationIsStoppedAndNothingKept) {
  const Outcome out = RunContested(ContestedLink::Mode::kReplace, 1);
  EXPECT_EQ(out.contested, 1);
  EXPECT_EQ(out.trial.end, host::TrialEnd::kWrongConfig);
  EXPECT_TRUE(out.trial.windows.empty());
  // Both configurations named: the one that runs by its digest (this bus does not
  // show the host another sender's frames, so not in words) and ours.
  char foreign[12];
  std::snprintf(foreign, sizeof foreign, "%08x", ConfigDigestOf(Foreign()));
  EXPECT_NE(out.trial.error.find(foreign), std::string::npos) << out.trial.error;
  EXPECT_NE(out.trial.error.find("6.0° × 3"), std::string::npos) << out.trial.error;
  // Stopped before its first window: far short of the other's 40°.
  EXPECT_EQ(out.final_state, app::BoardState::kIdle);
  EXPECT_LT(out.widest_setpoint_rad, 10.0 * kDeg);
}

}  // namespace
