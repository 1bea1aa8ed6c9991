#include "bus_trial_rig.h"

#include <atomic>
#include <mutex>
#include <thread>

#include "mjc/plant/params.h"
#include "mjc/sim/link_can_port.h"
#include "mjc/sim/scenarios.h"

namespace mjc::bus_trial {

using namespace mjc::protocol;

protocol::CanFrame Flood::Next() {
  const std::uint8_t other = static_cast<std::uint8_t>(2 + (n_ % 7));  // nodes 2..8
  CanFrame f;
  switch (n_++ % 6) {
    case 0:  // another board's telemetry
      f = Encode(TelemetryAngles{Angle::FromRaw(static_cast<std::int32_t>(rng_())),
                                 Angle::FromRaw(static_cast<std::int32_t>(rng_()))},
                 other);
      break;
    case 1:  // the host commanding another node
      f = Encode(Command{CommandCode::kStop, static_cast<std::uint8_t>(n_)}, other);
      break;
    case 2:  // a truncated setpoint for this node
      f = Encode(Setpoint{Angle::FromRaw(0), 0}, node_);
      f.length = 3;
      ++malformed_sent_;
      break;
    case 3:  // a parameter read for this node: every one needs a reply
      f = Encode(ParamRead{ParamId::kTelemetryAnglesHz}, node_);
      ++param_reads_sent_;
      break;
    case 4:  // an unused function code for this node
      f.id = MakeId(0x7F, node_);
      f.length = 8;
      break;
    default: {  // anything for another node: a random identifier, length, payload
      // (not 0x000: the emergency stop is every node's)
      do {
        f.id = static_cast<std::uint32_t>(rng_()) & 0x7FFu;
      } while (NodeOf(f.id) == node_ || f.id == IdOf<StopAll>(kEveryNode));
      f.length = static_cast<std::uint8_t>(rng_() % 9);
      for (auto& b : f.data) b = static_cast<std::uint8_t>(rng_());
      break;
    }
  }
  return f;
}

namespace {

// The board's port on the in-process bus, counting what passes: the host's frames in,
// the parameter replies out.
class CountingPort final : public hal::CanPort {
 public:
  explicit CountingPort(host::CanLink* link) : port_(link) {}
  std::uint32_t received = 0;
  std::uint32_t param_replies = 0;

 private:
  bool DoSend(const CanFrame& f) override {
    if (FunctionOf(f.id) == static_cast<std::uint8_t>(Function::kParamValue)) {
      ++param_replies;
    }
    return port_.Send(f);
  }
  bool DoReceive(CanFrame* f) override {
    if (!port_.Receive(f)) return false;
    ++received;
    return true;
  }
  std::uint32_t DoTakeBusOff() override { return port_.TakeBusOff(); }
  hal::CanPortCounters DoCounters() const override { return port_.counters(); }
  sim::LinkCanPort port_;
};

}  // namespace

BoardRun RunTrial(Flood* flood, int per_tick) {
  auto bus = host::InProcessBus::Create();
  auto board_link = bus->Connect();
  auto host_link = bus->Connect();

  plant::PlantParams params = plant::LoadPlantParams("default");
  params.interface = plant::LoadPlantParams("subject1").interface;
  CountingPort port(board_link.get());
  sim::SimBoard board(params, app::JointBoardConfig{app::DefaultJointConfig(), {}, 0, 1},
                      &port);
  Calibration cal;
  cal.backlash.c_right = Angle::Quantize(params.cable.c_right_rad);
  cal.backlash.c_left = Angle::Quantize(params.cable.c_left_rad);
  board.app().SetCalibration(cal);
  board.Tick();
  app::CanNode& node = board.board().node();

  BoardRun run;
  std::mutex truth_mutex;
  std::atomic<bool> stop{false};
  std::thread board_thread([&] {
    std::uint32_t last_tick = board.app().last().telemetry.tick;
    while (!stop) {
      for (int i = 0; flood != nullptr && i < per_tick; ++i) {
        node.HandleFrame(flood->Next());
        ++run.flooded;
      }
      {
        std::lock_guard lock(truth_mutex);
        const std::uint32_t tick = board.app().last().telemetry.tick + 1;
        if (run.truth_energy.size() <= tick) run.truth_energy.resize(tick + 1, 0.0);
        run.truth_energy[tick] = board.plant().truth().interface_energy_J;
      }
      board.Tick();
      ++run.ticks;
      const std::uint32_t tick = board.app().last().telemetry.tick;
      if (tick != last_tick + 1) ++run.tick_gaps;
      last_tick = tick;
      run.faulted = run.faulted || board.app().state() == app::BoardState::kFault;
      board.Poll();
    }
  });

  host::BoardClient client(host_link.get(), 1);
  TrialConfig config;
  config.amplitude = Angle::Quantize(15.0 * 3.14159265358979323846 / 180.0);
  config.frequency_mHz = 500;
  config.repetitions = 5;
  config.rest_100ms = 5;
  run.trial = host::RunBoardTrial(
      client, config, [&](const host::BoardWindow&) { ++run.progress_lines; });
  stop = true;
  board_thread.join();
  run.from_host = port.received;
  run.param_replies = port.param_replies;
  run.host_malformed = client.malformed();
  run.counters = node.counters();
  return run;
}

}  // namespace mjc::bus_trial
