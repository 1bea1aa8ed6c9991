// mjc monitor: live values of one or more boards (state, calibration, fault, angles,
// torque, power, energy), a line per node every interval stamped with the time (UTC),
// and a line for the bus once it has reported errors (error frames, bus-off). A node
// not heard yet reads "no data yet", never a line of zeros; one whose heartbeat stays
// away for two seconds is reported silent, and so is the exit status (Exit::kNoAnswer);
// two boards answering with one node id are reported, and the exit status is then
// Exit::kAmbiguous. --json prints one JSON object per line instead. While it runs it
// supervises: each node gets the host's heartbeat, so a motion still running when the
// monitor stops or dies is stopped by the board (kHostHeartbeatLost).
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "commands.h"
#include "mjc/host/board_client.h"
#include "mjc/host/describe.h"

namespace mjc::cli {
namespace {

// "2026-11-24T10:31:05.123Z" (full) or "10:31:05.123Z" (the time of day).
std::string Utc(std::chrono::system_clock::time_point t, bool full) {
  const auto ms =
      std::chrono::duration_cast<std::chrono::milliseconds>(t.time_since_epoch()).count();
  const std::time_t s = static_cast<std::time_t>(ms / 1000);
  std::tm tm{};
  gmtime_r(&s, &tm);
  char text[40];
  std::strftime(text, sizeof text, full ? "%Y-%m-%dT%H:%M:%S" : "%H:%M:%S", &tm);
  char out[48];
  std::snprintf(out, sizeof out, "%s.%03dZ", text, static_cast<int>(ms % 1000));
  return out;
}

}  // namespace

void AddMonitor(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "monitor", "Live values of boards on the bus; supervises them (host heartbeat)");
  static std::string iface;
  static std::vector<int> nodes;
  static double seconds = 0;
  static int interval_ms = 500;
  static bool json = false;
  static EstopOptions estop_options;
  AddIfaceOption(cmd, &iface);
  AddNodeOption(cmd, &nodes, "Node ids");
  cmd->add_option("--seconds", seconds, "Stop after this long (0: until SIGINT)")
      ->check(InRange(0, 1e9, "s"));
  cmd->add_option("--interval-ms", interval_ms, "Time between lines")
      ->check(InRange(50, 60000, "ms"))
      ->capture_default_str();
  cmd->add_flag("--json", json, "One JSON object per node (and bus report) and line");
  // Watched only when given: a monitor runs beside a trial, which may watch it.
  AddEstopOptions(cmd, &estop_options, EstopDefault::kGiven);
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
    // The monitor goes on after an emergency stop: it shows the boards' faults.
    const auto estop = StartEstop(estop_options, iface, "mjc monitor",
                                  boards.front()->session(), nullptr);
    std::uint64_t estops_shown = 0;
    std::string estop_error_shown;
    const auto start = std::chrono::steady_clock::now();
    std::vector<std::chrono::steady_clock::time_point> last_heard(boards.size(), start);
    std::vector<std::uint32_t> last_tick(boards.size(), 0);
    std::vector<bool> silent(boards.size(), false), ambiguous(boards.size(), false);
    std::string why;
    while (!stop) {
      const auto until =
          std::chrono::steady_clock::now() + std::chrono::milliseconds(interval_ms);
      while (std::chrono::steady_clock::now() < until && !stop) {
        for (auto& b : boards) {
          if (!b->Poll(5, &why)) throw Failure(why);
        }
      }
      const auto now = std::chrono::steady_clock::now();
      const auto wall = std::chrono::system_clock::now();
      const std::string stamp = Utc(wall, json);
      if (estop &&
          (estop->activations() != estops_shown || estop->error() != estop_error_shown)) {
        estops_shown = estop->activations();
        estop_error_shown = estop->error();
        const std::string what = EstopWhat(*estop);
        if (json) {
          const nlohmann::json j = {{"time", stamp},
                                    {"emergency_stop", estop->line_name()},
                                    {"activations", estops_shown},
                                    {"message", what}};
          std::printf("%s\n", j.dump().c_str());
        } else {
          std::printf("%s %s\n", stamp.c_str(), what.c_str());
        }
      }
      for (std::size_t i = 0; i < boards.size(); ++i) {
        const host::BoardClient& b = *boards[i];
        const host::BoardStatus& s = b.status();
        if (s.heard && s.tick != last_tick[i]) {
          last_heard[i] = now;
          last_tick[i] = s.tick;
        }
        const bool quiet = now - last_heard[i] > std::chrono::seconds(2);
        silent[i] = silent[i] || quiet;
        ambiguous[i] = ambiguous[i] || b.ambiguous();
        if (json) {
          nlohmann::json j = {{"time", stamp}, {"node", nodes[i]}, {"heard", s.heard}};
          j["silent"] = quiet;
          j["ambiguous"] = b.ambiguous();
          if (b.ambiguous()) j["message"] = b.AmbiguityMessage();
          if (s.heard) {
            j["state"] = host::StateName(s.state);
            j["calibrated"] = s.calibrated;
            j["fault"] = s.fault == Fault::kNone
                             ? nlohmann::json(nullptr)
                             : nlohmann::json{{"code", static_cast<int>(s.fault)},
                                              {"name", host::FaultName(s.fault)}};
            j["tick"] = s.tick;
            j["motor_rad"] = s.motor_rad;
            j["joint_rad"] = s.joint_rad;
            j["torque_Nm"] = s.torque_Nm;
            j["power_W"] = s.power_W;
            j["energy_J"] = s.energy_J;
            j["angle_frames_lost"] = b.angle_sequence().lost_frames();
          }
          if (const auto& info = b.info()) {
            j["build"] = host::BuildName(info->build, info->dirty);
            // Four lower-case hex digits, as mjc list --json and run.json write it.
            char instance[8];
            std::snprintf(instance, sizeof instance, "%04x", info->instance);
            j["instance"] = instance;
          }
          std::printf("%s\n", j.dump().c_str());
          continue;
        }
        if (b.ambiguous()) {
          std::printf("%s node %d: TWO BOARDS: %s\n", stamp.c_str(), nodes[i],
                      b.AmbiguityMessage().c_str());
          continue;
        }
        if (!s.heard) {
          std::printf("%s node %d: no data yet\n", stamp.c_str(), nodes[i]);
          continue;
        }
        if (quiet) {
          std::printf("%s node %d: silent (no heartbeat for 2 s)\n", stamp.c_str(),
                      nodes[i]);
          continue;
        }
        const std::string fault =
            s.fault == Fault::kNone ? "" : "  fault " + host::DescribeFault(s.fault);
        const std::uint64_t lost = b.angle_sequence().lost_frames();
        const std::string lost_text =
            lost == 0 ? "" : "  " + std::to_string(lost) + " angle frame(s) lost";
        std::printf(
            "%s node %d: %-11s %-12s θm %+8.4f rad  θj %+8.4f rad  τ %+7.4f N·m  "
            "P %+8.3f mW  E %9.3f mJ%s%s\n",
            stamp.c_str(), nodes[i], std::string(host::StateName(s.state)).c_str(),
            s.calibrated ? "calibrated" : "uncalibrated", s.motor_rad, s.joint_rad,
            s.torque_Nm, s.power_W * 1e3, s.energy_J * 1e3, fault.c_str(),
            lost_text.c_str());
      }
      const host::LinkStats& bus = links.front()->stats();
      if (bus.error_frames > 0) {
        if (json) {
          std::printf("%s\n", nlohmann::json{{"time", stamp},
                                             {"iface", iface},
                                             {"error_frames", bus.error_frames},
                                             {"bus_off", bus.bus_off}}
                                  .dump()
                                  .c_str());
        } else {
          std::printf("%s %s: %llu error frames since start, %llu of them bus-off%s\n",
                      stamp.c_str(), iface.c_str(),
                      static_cast<unsigned long long>(bus.error_frames),
                      static_cast<unsigned long long>(bus.bus_off),
                      bus.bus_off > 0 ? " (BUS-OFF)" : "");
        }
      }
      // A closed stdout (`mjc monitor | head`: SIGPIPE is ignored) ends the monitor as a
      // failure to write, not a loop writing into nothing.
      if (std::fflush(stdout) != 0 || std::ferror(stdout)) {
        throw Failure(std::string("error writing stdout: ") + std::strerror(errno));
      }
      if (seconds > 0 && now - start >= std::chrono::duration<double>(seconds)) break;
    }
    std::string failures;
    Exit worst = Exit::kOk;
    for (std::size_t i = 0; i < boards.size(); ++i) {
      std::string what;
      if (ambiguous[i]) {
        what = boards[i]->AmbiguityMessage();
        worst = Exit::kAmbiguous;
      } else if (silent[i]) {
        what = host::SilentNode(nodes[i], iface);
        if (worst == Exit::kOk) worst = Exit::kNoAnswer;
      }
      if (!what.empty()) failures += (failures.empty() ? "" : "; ") + what;
    }
    if (worst != Exit::kOk) throw Failure(worst, failures);
  });
}

}  // namespace mjc::cli
