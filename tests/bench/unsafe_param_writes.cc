// Writes that would loosen or switch off a protection, sent raw to the simulated board
// (the firmware's application and CAN node on the plant) over an in-process bus, as a
// tool that skipped the host's checks (or a hand-typed cansend) would send them; for
// ./bench: "unsafe_param_writes_accepted: N writes (of M ...)", how many the board
// took (goal 0). The joint's description (robots/maestro-default.json: 1 N·m, −45° to
// 90°) is sent first, as mjc calibrate --robot sends it; some writes are sent while a
// calibration sweep runs. Each refusal is listed on stderr with the bound it named.
#include <atomic>
#include <cmath>
#include <cstdio>
#include <string>
#include <thread>
#include <vector>

#include "mjc/app/joint_config.h"
#include "mjc/host/describe.h"
#include "mjc/host/joint_limits.h"
#include "mjc/host/param_io.h"
#include "mjc/plant/params.h"
#include "mjc/sim/link_can_port.h"
#include "mjc/sim/sim_board.h"

namespace {

using namespace mjc;
using protocol::ParamId;

constexpr std::uint8_t kNode = 1;
constexpr int kTimeoutMs = 1000;

struct Write {
  ParamId id;
  double value;  // in the list's units
  const char* why;
};

// The list's entry of an id it has.
const protocol::ParamInfo& InfoOf(ParamId id) {
  for (const protocol::ParamInfo& p : protocol::kParams) {
    if (p.id == id) return p;
  }
  return protocol::kParams[0];  // not reached: the ids named here are the list's
}

// The raw integer of `value` in `id`'s format, saturated to 32 bits.
std::int32_t Raw(ParamId id, double value) {
  const double raw = std::ldexp(value, InfoOf(id).frac_bits);
  return static_cast<std::int32_t>(
      std::fmax(std::fmin(raw, 2147483647.0), -2147483648.0));
}

}  // namespace

int main() {
  std::shared_ptr<host::InProcessBus> bus = host::InProcessBus::Create();
  std::unique_ptr<host::CanLink> board_link = bus->Connect();
  std::unique_ptr<host::CanLink> host_link = bus->Connect();
  sim::LinkCanPort port(board_link.get());
  app::JointBoardConfig config{app::DefaultJointConfig(), {}, 0, 1};
  config.can.node = kNode;
  sim::SimBoard board(plant::LoadPlantParams("default"), config, &port);
  host::BoardClient client(host_link.get(), kNode);
  std::atomic<bool> stop{false};
  std::thread thread([&] {
    while (!stop) {
      board.Tick();
      board.Poll();
    }
  });
  int failed = 0, sent = 0, taken = 0;
  std::string why;
  const auto fail = [&](const std::string& what) {
    std::fprintf(stderr, "unsafe_param_writes: %s\n", what.c_str());
    ++failed;
  };
  const auto send = [&](const Write& w) {
    const protocol::ParamInfo& info = InfoOf(w.id);
    const auto answer = client.WriteParam(w.id, Raw(w.id, w.value), kTimeoutMs, &why);
    if (!answer) return fail(std::string(info.key) + ": no answer: " + why);
    ++sent;
    const bool ok = answer->status == protocol::ParamStatus::kOk;
    if (ok) ++taken;
    std::fprintf(
        stderr, "  %s = %g (%s): %s%s\n", info.key, w.value, w.why,
        ok ? "TAKEN" : std::string(host::ParamStatusName(answer->status)).c_str(),
        ok || answer->status == protocol::ParamStatus::kRefusedNotIdle
            ? ""
            : (", " + host::FormatParamWithUnit(info, answer->value)).c_str());
  };

  host::WaitEnd end{};
  if (!client.Identify(&end, &why)) fail("the board did not answer: " + why);
  // The joint's description, as mjc calibrate --robot sends it.
  const host::RobotDescription joint;  // maestro-default's limits: 1 N·m, −45°..90°
  const host::ParamWriteOutcome limits = host::SendJointLimits(client, joint, kTimeoutMs);
  if (limits.end != host::ParamWriteEnd::kDone) fail("the joint's limits: " + limits.why);

  const Write at_rest[] = {
      {ParamId::kHostTimeoutMs, 0, "supervision off"},
      {ParamId::kHostTimeoutMs, 60000, "a minute of orphan motion"},
      {ParamId::kStreamTimeoutMs, 0, "streaming unsupervised"},
      {ParamId::kStreamTimeoutMs, 60000, "a minute on a stale setpoint"},
      {ParamId::kHeartbeatHz, 0, "no tool reaches the board"},
      {ParamId::kHeartbeatHz, 10000, "a bus flooded by one board"},
      {ParamId::kTorqueMax, 100, "100 N.m on a joint rated 1"},
      {ParamId::kTorqueMax, 2, "beyond the joint's 1 N.m"},
      {ParamId::kJointTorqueLimit, 5, "the joint's rating loosened"},
      {ParamId::kJointAngleMax, 1.6, "the joint's 90° flexion loosened"},
      {ParamId::kJointAngleMin, -1.6, "the joint's -45° extension loosened"},
      {ParamId::kVelocityMax, 50, "ten times the velocity ceiling"},
      {ParamId::kPositionKp, 1000, "a gain in the wrong unit"},
      {ParamId::kPositionKi, 20000, "an integrator at its stability bound"},
      {ParamId::kPositionKd, 100, "a derivative gain in the wrong unit"},
      {ParamId::kPositionKff, 100, "a feed-forward in the wrong unit"},
  };
  for (const Write& w : at_rest) send(w);

  // While a calibration sweep runs: within range, but the motion started under others.
  protocol::SweepConfig sweep;
  sweep.end_amplitude = Angle::Quantize(0.05);
  sweep.frequency_mHz = 100;
  sweep.repetitions = 255;
  sweep.rest_100ms = 0;
  const auto started = client.Start(sweep, host::kStartAnswerMs, &why);
  if (!started || *started != protocol::CommandOutcomeCode::kAccepted) {
    fail("the sweep did not start: " + why);
  } else if (!client.Await(
                 [&] {
                   return client.status().state == protocol::BoardState::kCalibrating;
                 },
                 {std::chrono::seconds(5)}, &end, &why)) {
    fail("the sweep was not seen running: " + why);
  } else {
    const Write moving[] = {
        {ParamId::kHostTimeoutMs, 1000, "supervision loosened mid-motion"},
        {ParamId::kStreamTimeoutMs, 100, "stream timeout loosened mid-motion"},
        {ParamId::kTorqueMax, 1, "torque limit changed mid-motion"},
        {ParamId::kPositionKp, 400, "the loop's gain changed mid-motion"},
    };
    for (const Write& w : moving) send(w);
    (void)client.Command(protocol::CommandCode::kStop, kTimeoutMs, &why);
  }
  stop = true;
  thread.join();
  if (failed != 0) return 1;
  std::printf(
      "unsafe_param_writes_accepted: %d writes (of %d that would loosen or switch off a "
      "protection, sent raw to the simulated board)\n",
      taken, sent);
  return 0;
}
