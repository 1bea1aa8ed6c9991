// mjc monitor: live values of one or more boards (state, calibration, fault, angles,
// torque, power, energy), a line per node every interval. A node that has not sent a
// heartbeat for two seconds is reported silent; the exit status is 3 if any was.
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <memory>
#include <vector>

#include "commands.h"
#include "mjc/host/board_client.h"

namespace mjc::cli {
namespace {

std::atomic<bool> g_stop{false};
void OnSignal(int) { g_stop = true; }

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

void AddMonitor(CLI::App& app, int* status) {
  auto* cmd = app.add_subcommand("monitor", "Live values of boards on the bus");
  static std::string iface = "vcan0";
  static std::vector<int> nodes = {1};
  static double seconds = 0;
  static int interval_ms = 500;
  cmd->add_option("--iface", iface, "CAN interface")->capture_default_str();
  cmd->add_option("--node", nodes, "Node ids")
      ->check(CLI::Range(1, 8))
      ->capture_default_str();
  cmd->add_option("--seconds", seconds, "Stop after this long (0: until SIGINT)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--interval-ms", interval_ms, "Time between lines")
      ->check(CLI::Range(50, 60000))
      ->capture_default_str();
  cmd->callback([status] {
    std::string why;
    std::vector<std::unique_ptr<host::SocketCanLink>> links;
    std::vector<std::unique_ptr<host::BoardClient>> boards;
    for (int node : nodes) {
      auto link = host::SocketCanLink::Open(iface, &why);
      if (!link) {
        std::fprintf(stderr, "mjc monitor: %s\n", why.c_str());
        *status = 1;
        return;
      }
      boards.push_back(std::make_unique<host::BoardClient>(
          link.get(), static_cast<std::uint8_t>(node)));
      links.push_back(std::move(link));
    }
    std::signal(SIGINT, OnSignal);
    std::signal(SIGTERM, OnSignal);
    const auto start = std::chrono::steady_clock::now();
    std::vector<std::chrono::steady_clock::time_point> last_heard(boards.size(), start);
    std::vector<std::uint32_t> last_tick(boards.size(), 0);
    bool any_silent = false;
    while (!g_stop) {
      const auto until =
          std::chrono::steady_clock::now() + std::chrono::milliseconds(interval_ms);
      while (std::chrono::steady_clock::now() < until) {
        for (auto& b : boards) {
          if (!b->Poll(5, &why)) {
            std::fprintf(stderr, "mjc monitor: %s\n", why.c_str());
            *status = 1;
            return;
          }
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
          any_silent = true;
          continue;
        }
        std::printf(
            "node %d: %-11s %-12s fault %3d  θm %+8.4f rad  θj %+8.4f rad  τ %+7.4f N·m  "
            "P %+8.3f mW  E %9.3f mJ\n",
            nodes[i], StateName(s.state), s.calibrated ? "calibrated" : "uncalibrated",
            static_cast<int>(s.fault), s.motor_rad, s.joint_rad, s.torque_Nm,
            s.power_W * 1e3, s.energy_J * 1e3);
      }
      std::fflush(stdout);
      if (seconds > 0 && now - start >= std::chrono::duration<double>(seconds)) break;
    }
    *status = any_silent ? 3 : 0;
  });
}

}  // namespace mjc::cli
