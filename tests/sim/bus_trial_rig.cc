#include "bus_trial_rig.h"

#include <numbers>

#include "mjc/app/joint_config.h"
#include "mjc/plant/params.h"
#include "mjc/sim/bus_board.h"

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

BoardRun RunTrial(Flood* flood, int per_tick) {
  plant::PlantParams params = plant::LoadPlantParams("default");
  params.interface = plant::LoadPlantParams("subject1").interface;
  sim::BusBoard bus(params, app::DefaultJointConfig());
  Calibration cal;
  cal.backlash.c_right = Angle::Quantize(params.cable.c_right_rad);
  cal.backlash.c_left = Angle::Quantize(params.cable.c_left_rad);
  bus.app().SetCalibration(cal);
  bus.Run(1);
  app::CanNode& node = bus.board().board().node();

  // The board's side: the flood into its CAN node and the plant's truth before every
  // tick, the tick's counter and state after it.
  BoardRun run;
  std::uint32_t last_tick = bus.app().last().telemetry.tick;
  bus.SetBeforeTick([&](sim::SimBoard& board) {
    for (int i = 0; flood != nullptr && i < per_tick; ++i) {
      node.HandleFrame(flood->Next());
      ++run.flooded;
    }
    const std::uint32_t tick = board.app().last().telemetry.tick + 1;
    if (run.truth_energy.size() <= tick) run.truth_energy.resize(tick + 1, 0.0);
    run.truth_energy[tick] = board.plant().truth().interface_energy_J;
  });
  bus.SetAfterTick([&](sim::SimBoard& board) {
    ++run.ticks;
    const std::uint32_t tick = board.app().last().telemetry.tick;
    if (tick != last_tick + 1) ++run.tick_gaps;
    last_tick = tick;
    run.faulted = run.faulted || board.app().state() == app::BoardState::kFault;
  });

  // The host's side: mjc trial's runner on the bus's client.
  host::BoardClient& client = bus.client();
  TrialConfig config;
  config.amplitude = Angle::Quantize(15.0 * std::numbers::pi / 180.0);
  config.frequency_mHz = 500;
  config.repetitions = 5;
  config.rest_100ms = 5;
  run.trial = host::RunBoardTrial(
      client, config, [&](const host::BoardWindow&) { ++run.progress_lines; });
  bus.SetBeforeTick(nullptr);
  bus.SetAfterTick(nullptr);
  run.from_host = bus.from_host();
  run.param_replies = bus.sent(Function::kParamValue);
  run.host_malformed = client.malformed();
  run.counters = node.counters();
  return run;
}

}  // namespace mjc::bus_trial
