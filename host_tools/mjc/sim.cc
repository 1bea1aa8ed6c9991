// mjc sim: a simulated joint board on a CAN interface. The unmodified firmware
// application and CAN node run against the plant model at the board's tick rate, paced
// to wall time (or --speed times faster), so the other mjc commands, can-utils and any
// CAN tool see a board on the bus.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <numeric>
#include <random>
#include <thread>

#include "commands.h"
#include "hal/sim/sim_flash.h"
#include "mjc/app/joint_board.h"
#include "mjc/app/joint_config.h"
#include "mjc/build_id.h"
#include "mjc/host/can_link.h"
#include "mjc/plant/params.h"
#include "mjc/sim/link_can_port.h"
#include "mjc/sim/sim_board.h"

namespace mjc::cli {
namespace {

// SIGUSR1 raises the joint encoder's error flag until SIGUSR2 clears it: a sensor fault
// whose cause stays present, on demand, for the tools' fault handling (a clear is then
// refused until SIGUSR2).
std::atomic<int> g_sensor_fault{0};  // +1 raise, -1 clear, 0 nothing new
void OnSensorFaultSignal(int signal) { g_sensor_fault = signal == SIGUSR1 ? 1 : -1; }

// Ticks between two passes of the board's main loop and two reads of the clock: 1 ms
// at the board's 10 kHz.
constexpr std::uint64_t kPollEveryTicks = 10;

}  // namespace

void AddSim(CLI::App& app) {
  auto* cmd = app.add_subcommand("sim", "Run a simulated joint board on a CAN interface");
  cmd->footer(
      std::string(kExitStatusHelp) +
      "\n\nSignals: SIGUSR1 makes the joint encoder flag an error (fault 101) until "
      "SIGUSR2. "
      "A bus-off error frame on the interface is taken as the board's own bus-off.");
  static std::string iface, robot = "default", subject, flash_path;
  static int node = 1;
  static double seconds = 0, speed = 1;
  AddIfaceOption(cmd, &iface);
  AddNodeOption(cmd, &node);
  cmd->add_option("--robot", robot, "Plant parameter set of the robot (name or .json)")
      ->capture_default_str();
  cmd->add_option("--subject", subject,
                  "Don this subject's interface (name or .json); none: robot alone");
  cmd->add_option("--seconds", seconds,
                  "Stop after this much simulated time (0: until SIGINT/SIGTERM)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option(
      "--flash", flash_path,
      "Keep the board's flash (its stored calibration) in this file across runs");
  cmd->add_option("--speed", speed,
                  "Simulated seconds per wall second (0: as fast as possible)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->callback([] {
    std::string why;
    auto link = OpenLink(iface);
    auto load = [](const std::string& s) {
      return s.find('/') != std::string::npos || s.ends_with(".json")
                 ? plant::LoadPlantParamsFile(s)
                 : plant::LoadPlantParams(s);
    };
    plant::PlantParams params = load(robot);
    if (!subject.empty()) params.interface = load(subject).interface;
    app::JointBoardConfig config{app::DefaultJointConfig(), {}, 0, 1};
    app::CanNodeConfig& node_config = config.can;
    node_config.node = static_cast<std::uint8_t>(node);
    // Who this board is: this build, just powered on, and an identity of its own
    // drawn at random (a board's comes from its chip's unique id).
    node_config.identity.build = build::kCommit;
    node_config.identity.dirty = build::kDirty;
    node_config.identity.reset_cause = protocol::ResetCause::kPowerOn;
    node_config.identity.instance = static_cast<std::uint16_t>(std::random_device{}());
    // A host's heartbeats come every 100 ms of wall time, `speed` times as much board
    // time: the board's supervision timeout scales with it, so it still means 300 ms of
    // wall time, and is off at speed 0, where wall time means nothing to the board.
    node_config.host_timeout_ms =
        speed == 0 ? std::uint16_t{0}
                   : static_cast<std::uint16_t>(std::clamp(
                         std::lround(node_config.host_timeout_ms * speed), 1L, 60000L));
    // Flash: two 2 KB pages for the calibration's A/B records, as on the board.
    hal::SimFlash flash(2, flash_path, &why);
    if (!why.empty()) std::fprintf(stderr, "mjc sim: %s\n", why.c_str());
    // The board's CAN controller is the link: its error frames stand for the
    // controller's own (a bus-off report is the driver's bus-off interrupt).
    sim::LinkCanPort port(link.get());
    sim::SimBoard board(params, config, &port, &flash);
    if (const auto restored = board.board().Boot()) {
      std::fprintf(stderr, "mjc sim: restored calibration #%u from flash\n",
                   restored->sequence);
    } else {
      std::fprintf(stderr, "mjc sim: no stored calibration: uncalibrated\n");
    }
    const std::atomic<bool>& stop = StopOnSignals();
    std::signal(SIGUSR1, OnSensorFaultSignal);
    std::signal(SIGUSR2, OnSensorFaultSignal);
    std::fprintf(
        stderr, "mjc sim: node %d on %s (%s%s)\n", node, iface.c_str(), robot.c_str(),
        subject.empty() ? ", robot alone" : (", " + subject + " donned").c_str());
    const double period = board.tick_period_s();
    std::uint64_t ticks = 0;
    // Pacing: tick n is due at origin + n·period/speed. A board that falls behind (a
    // loaded machine) does not race to catch up, which would crowd a burst of its time
    // between two of a host's heartbeats; it moves its origin instead and says so.
    using Clock = std::chrono::steady_clock;
    const auto started = Clock::now();
    auto origin = started;
    std::uint64_t origin_tick = 0;
    double lost_s = 0;  // wall time the board fell behind its speed, in all
    bool warned = false;
    std::uint32_t bus_off_seen = 0;
    while (!stop && (seconds == 0 || static_cast<double>(ticks) * period < seconds)) {
      // The main loop's pass once a millisecond of board time: under emulation each
      // read of the socket is a system call, and reading it every 100 µs tick cost
      // more than the plant (41 % of a QEMU TCG vCPU for a board at speed 1, half of
      // it in the kernel). A frame waits at most 1 ms.
      if (ticks % kPollEveryTicks == 0) {
        board.Poll();
        if (port.failed()) throw Failure(port.error());
        for (; bus_off_seen < board.board().node().counters().bus_off; ++bus_off_seen) {
          std::fprintf(stderr,
                       "mjc sim: %s: bus-off at %.4f s: motor stopped (fault 303) until "
                       "the host clears it\n",
                       iface.c_str(), static_cast<double>(ticks) * period);
        }
      }
      if (const int fault = g_sensor_fault.exchange(0); fault != 0) {
        if (fault > 0) {
          board.plant().InjectFault({plant::SensorFaultKind::kJointErrorFlag, 0, 0});
        } else {
          board.plant().ClearFaults();
        }
        std::fprintf(stderr, "mjc sim: joint encoder error flag %s at %.4f s\n",
                     fault > 0 ? "raised" : "cleared",
                     static_cast<double>(ticks) * period);
      }
      board.Tick();
      ++ticks;
      // Paced a millisecond of board time at a time: reading the clock costs a system
      // call in a virtual machine whose clock source is emulated (HPET under QEMU TCG).
      if (speed > 0 && ticks % kPollEveryTicks == 0) {
        const auto due =
            origin +
            std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(
                static_cast<double>(ticks - origin_tick) * period / speed));
        const auto now = Clock::now();
        if (now - due > std::chrono::milliseconds(20)) {
          lost_s += std::chrono::duration<double>(now - due).count();
          origin = now;
          origin_tick = ticks;
          if (!warned) {
            warned = true;
            std::fprintf(
                stderr,
                "mjc sim: cannot keep --speed %g on this machine: the board runs "
                "at its own slower pace (the summary says how slow)\n",
                speed);
          }
        } else if (due - now > std::chrono::milliseconds(20)) {
          // Sleeps only once 20 ms of lead have built up: in a virtual machine (QEMU
          // TCG) sleeping and waking cost more than simulating — a board at speed 1
          // took 41 % of a vCPU sleeping every tick, 25 % every 5 ms, 19 % every 20 ms.
          // A host's frame waits at most that long; its heartbeat comes every 100 ms.
          std::this_thread::sleep_until(due);
        }
      }
    }
    // What reached the socket before the stop is the board's to account for: a
    // sender that has finished has put all of it there.
    for (protocol::CanFrame f; port.Receive(&f);) board.board().node().HandleFrame(f);
    const app::CanNodeCounters c = board.board().node().counters();
    const double simulated_s = static_cast<double>(ticks) * period;
    const double wall_s = std::chrono::duration<double>(Clock::now() - started).count();
    if (speed > 0) {
      std::fprintf(stderr, "mjc sim: speed %.2f of %g asked (%.1f s behind in all)\n",
                   wall_s > 0 ? simulated_s / wall_s : 0.0, speed, lost_s);
    }
    std::fprintf(
        stderr,
        "mjc sim: %.1f s simulated; frames sent %llu (send failures %llu), handled %u, "
        "ignored %u, malformed %u, rx dropped %llu, tx dropped %u, bus-off %u\n",
        simulated_s, static_cast<unsigned long long>(link->stats().sent),
        static_cast<unsigned long long>(link->stats().tx_failed), c.handled, c.ignored,
        std::accumulate(c.malformed.begin(), c.malformed.end(), 0u),
        static_cast<unsigned long long>(link->stats().rx_dropped), c.tx_dropped,
        c.bus_off);
  });
}

}  // namespace mjc::cli
