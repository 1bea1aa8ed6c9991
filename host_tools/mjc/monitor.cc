// mjc monitor: live values of one or more boards (state, calibration, fault, angles,
// torque, power, energy), a line per node every interval, and a line for the bus once
// it has reported errors (error frames, bus-off). A node that has not sent a heartbeat
// for two seconds is reported silent; the exit status is then Exit::kNoAnswer. While it
// runs it supervises: each node gets the host's heartbeat, so a motion still running
// when the monitor stops or dies is stopped by the board (kHostHeartbeatLost).
#include <atomic>
#include <chrono>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "commands.h"
#include "mjc/host/board_client.h"
#include "mjc/host/describe.h"

namespace mjc::cli {
namespace {

const char* StateName(protocol::BoardState s) {
  switch (s) {
    case protocol::BoardState::kIdle:
      return "idle";
    case protocol::BoardState::kCalibrating:
      return "calibrating";
    case protocol::BoardState::kRunning:
      return "running";
    case protocol::BoardState::kFault:
      return "FAULT";
  }
  return "?";
}

}  // namespace

void AddMonitor(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "monitor", "Live values of boards on the bus; supervises them (host heartbeat)");
  static std::string iface;
  static std::vector<int> nodes = {1};
  static double seconds = 0;
  static int interval_ms = 500;
  AddIfaceOption(cmd, &iface);
  AddNodeOption(cmd, &nodes, "Node ids");
  cmd->add_option("--seconds", seconds, "Stop after this long (0: until SIGINT)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--interval-ms", interval_ms, "Time between lines")
      ->check(CLI::Range(50, 60000))
      ->capture_default_str();
  cmd->callback([] {
    // A link per node: each client filters its link to its own node.
    std::vector<std::unique_ptr<host::SocketCanLink>> links;
    std::vector<std::unique_ptr<host::BoardClient>> boards;
    for (int node : nodes) {
      links.push_back(OpenLink(iface));
      boards.push_back(std::make_unique<host::BoardClient>(
          links.back().get(), static_cast<std::uint8_t>(node),
          host::HostHeartbeats::kSend));
    }
    // Every link sees the interface's error frames: the first one's tell of them.
    SayBusOff(*boards.front(), "mjc monitor", iface);
    const std::atomic<bool>& stop = StopOnSignals();
    const auto start = std::chrono::steady_clock::now();
    std::vector<std::chrono::steady_clock::time_point> last_heard(boards.size(), start);
    std::vector<std::uint32_t> last_tick(boards.size(), 0);
    std::string silent;
    std::string why;
    while (!stop) {
      const auto until =
          std::chrono::steady_clock::now() + std::chrono::milliseconds(interval_ms);
      while (std::chrono::steady_clock::now() < until) {
        for (auto& b : boards) {
          if (!b->Poll(5, &why)) throw Failure(why);
        }
      }
      const auto now = std::chrono::steady_clock::now();
      for (std::size_t i = 0; i < boards.size(); ++i) {
        const host::BoardStatus& s = boards[i]->status();
        if (s.heard && s.tick != last_tick[i]) {
          last_heard[i] = now;
          last_tick[i] = s.tick;
        }
        if (now - last_heard[i] > std::chrono::seconds(2)) {
          std::printf("node %d: silent (no heartbeat for 2 s)\n", nodes[i]);
          const std::string id = std::to_string(nodes[i]);
          if (silent.find(" " + id + ",") == std::string::npos) silent += " " + id + ",";
          continue;
        }
        const std::string fault =
            s.fault == Fault::kNone ? "" : "  fault " + host::DescribeFault(s.fault);
        std::printf(
            "node %d: %-11s %-12s θm %+8.4f rad  θj %+8.4f rad  τ %+7.4f N·m  "
            "P %+8.3f mW  E %9.3f mJ%s\n",
            nodes[i], StateName(s.state), s.calibrated ? "calibrated" : "uncalibrated",
            s.motor_rad, s.joint_rad, s.torque_Nm, s.power_W * 1e3, s.energy_J * 1e3,
            fault.c_str());
      }
      const host::LinkStats& bus = links.front()->stats();
      if (bus.error_frames > 0) {
        std::printf("%s: %llu error frames since start, %llu of them bus-off%s\n",
                    iface.c_str(), static_cast<unsigned long long>(bus.error_frames),
                    static_cast<unsigned long long>(bus.bus_off),
                    bus.bus_off > 0 ? " (BUS-OFF)" : "");
      }
      std::fflush(stdout);
      if (seconds > 0 && now - start >= std::chrono::duration<double>(seconds)) break;
    }
    if (!silent.empty()) {
      silent.pop_back();
      throw Failure(Exit::kNoAnswer, "silent node(s):" + silent);
    }
  });
}

}  // namespace mjc::cli
