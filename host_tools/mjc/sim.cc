// mjc sim: a simulated joint board on a CAN interface, from its reset on, as the chip
// runs: its CAN bootloader (the real logic, over the board's whole flash) and then the
// unmodified firmware application and CAN node against the plant model, at the board's
// tick rate, paced to wall time (or --speed times faster), so the other mjc commands,
// can-utils and any CAN tool see a board on the bus, and mjc flash can update it.
//
// The board's flash (--flash FILE, else memory) holds its image, its identity and its
// calibration. A new one is a board fresh from the factory: an image of this mjc's
// build installed (a stand-in: the host cannot run the ARM image, so the board runs the
// host build of the application and reports the build in the installed image's header,
// sim::BootingBoard) and its node id commissioned. Killing the process is a power cut;
// starting it again on the same file is the power-up. --reset-line gives it an NRST on
// a GPIO line: held low, the board stays in reset; released, it starts anew.
#include <sys/stat.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <numeric>
#include <random>
#include <thread>

#include "commands.h"
#include "hal/sim/sim_flash.h"
#include "mjc/app/joint_board.h"
#include "mjc/app/joint_config.h"
#include "mjc/boot/identity_store.h"
#include "mjc/boot/layout.h"
#include "mjc/build_id.h"
#include "mjc/host/can_link.h"
#include "mjc/host/describe.h"
#include "mjc/host/robot_description.h"
#include "mjc/plant/params.h"
#include "mjc/sim/booting_board.h"
#include "mjc/sim/link_can_port.h"
#include "mjc/sim/robot_plant.h"

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

// The lead over wall time at which the board waits: 20 ms (see the loop). In the
// bootloader the wait ends at the first frame, which it then answers at once.
constexpr auto kMostLead = std::chrono::milliseconds(20);

// The chip's unique id, folded to 16 bits (both images report it): one per flash file,
// so a board keeps its instance over restarts as a chip does; a board without a file
// draws one.
std::uint16_t InstanceFor(const std::string& flash_path) {
  if (flash_path.empty()) return static_cast<std::uint16_t>(std::random_device{}());
  std::error_code error;
  const auto path = std::filesystem::weakly_canonical(flash_path, error);
  const std::size_t h = std::hash<std::string>{}(error ? flash_path : path.string());
  return static_cast<std::uint16_t>(h ^ (h >> 16) ^ (h >> 32) ^ (h >> 48));
}

// What the board did, as stderr lines.
void Tell(const sim::BoardEvent& e, const std::string& iface, const std::string& robot,
          const std::string& subject) {
  using Kind = sim::BoardEvent::Kind;
  switch (e.kind) {
    case Kind::kReset:
      if (e.cause != protocol::ResetCause::kPowerOn) {
        std::fprintf(stderr, "mjc sim: reset (%s)\n",
                     std::string(host::ResetCauseName(e.cause)).c_str());
      }
      return;
    case Kind::kEnterBootloader:
      std::fprintf(stderr,
                   "mjc sim: node %d: entering the bootloader (a host's BootHold)\n",
                   e.node);
      return;
    case Kind::kApplication:
      std::fprintf(
          stderr, "mjc sim: node %d on %s (%s%s): build %s, the installed image's\n",
          e.node, iface.c_str(), robot.c_str(),
          subject.empty() ? ", robot alone" : (", " + subject + " donned").c_str(),
          host::BuildName(e.build, e.dirty).c_str());
      if (e.calibration) {
        std::fprintf(stderr, "mjc sim: restored calibration #%u from flash\n",
                     *e.calibration);
      } else {
        std::fprintf(stderr, "mjc sim: no stored calibration: uncalibrated\n");
      }
      return;
    case Kind::kBootloader:
      break;
  }
  protocol::BootStatus status;
  status.state = e.state;
  status.reason = e.reason;
  status.error = e.error;
  status.progress_permille = e.progress_permille;
  switch (e.state) {
    case protocol::BootState::kHoldWindow:
      return;  // the usual start: it hands over 200 ms later
    case protocol::BootState::kReceiving:
      std::fprintf(stderr, "mjc sim: node %d: bootloader: receiving an image, %u%%\n",
                   e.node, e.progress_permille / 10u);
      return;
    case protocol::BootState::kCommitted:
      std::fprintf(stderr, "mjc sim: node %d: bootloader: image %s committed\n", e.node,
                   host::BuildName(e.build, e.dirty).c_str());
      return;
    case protocol::BootState::kReady:
      std::fprintf(stderr, "mjc sim: node %d: bootloader stays: %s\n", e.node,
                   host::DescribeBootStatus(status).c_str());
      return;
  }
}

}  // namespace

void AddSim(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "sim",
      "Run a simulated joint board (its bootloader, then its application) on a CAN "
      "interface");
  cmd->footer(
      std::string(kExitStatusHelp) +
      "\n\nThe board starts as the chip does: its bootloader checks the installed image "
      "and hands over after its 200 ms hold window, or stays (no valid image, held by a "
      "host, three unconfirmed starts) and takes an image (mjc flash). The host cannot "
      "run the ARM image: it runs the host build of the application and reports the "
      "build in the installed image's header. Killing mjc sim is a power cut; starting "
      "it again on the same --flash file is the power-up.\n\n"
      "Signals: SIGUSR1 makes the joint encoder flag an error (fault 101) until "
      "SIGUSR2. "
      "A bus-off error frame on the interface is taken as the board's own bus-off.");
  static std::string iface, robot = "default", subject, flash_path, reset_name,
                            robot_description;
  static int node = 1;
  static double seconds = 0, speed = 1;
  AddIfaceOption(cmd, &iface);
  static CLI::Option* node_option = nullptr;
  node_option = AddNodeOption(
      cmd, &node,
      "Node id of a new board (commissioned into its flash); a board's flash keeps its "
      "own",
      false);
  cmd->add_option("--robot", robot, "Plant parameter set of the robot (name or .json)")
      ->capture_default_str();
  cmd->add_option("--robot-description", robot_description,
                  "A joint's robot description (robots/*.json): the plant set with its "
                  "α = r_m/r_j, springs and encoder zeros");
  cmd->add_option("--subject", subject,
                  "Don this subject's interface (name or .json); none: robot alone");
  cmd->add_option("--seconds", seconds,
                  "Stop after this much simulated time (0: until SIGINT/SIGTERM)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option(
      "--flash", flash_path,
      "The board's whole flash (512 KB: firmware image, node id, calibration) "
      "in this file, kept across runs; a new file is a board fresh from the "
      "factory with this mjc's image installed");
  cmd->add_option("--speed", speed,
                  "Simulated seconds per wall second (0: as fast as possible; the "
                  "bootloader then keeps real time, its timeouts are about a host's "
                  "frames)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->add_option("--reset-line", reset_name,
                  "The board's NRST: a GPIO input CHIP:LINE, active low (a host's reset "
                  "line wired to it: held low, the board stays in reset; released, it "
                  "starts anew, reset cause pin)")
      ->check(LineSpecCheck(false));
  cmd->callback([] {
    std::string why;
    auto link = OpenLink(iface);
    // The NRST pin, watched for the edge into its active (low) level.
    std::unique_ptr<gpio::EdgeInput> nrst;
    if (const auto spec = LineOf(reset_name)) {
      gpio::LineOptions options;
      options.consumer = "mjc sim nrst";
      options.active_low = true;
      nrst = gpio::OpenEdgeInput(*spec, options, &why);
      if (!nrst) throw Failure("reset line: " + why);
    }
    auto load = [](const std::string& s) {
      return s.find('/') != std::string::npos || s.ends_with(".json")
                 ? plant::LoadPlantParamsFile(s)
                 : plant::LoadPlantParams(s);
    };
    plant::PlantParams params = load(robot);
    if (!robot_description.empty()) {
      const auto described = host::LoadRobotDescription(robot_description, &why);
      if (!described) throw Failure("robot description refused: " + why);
      params = sim::PlantForRobot(*described, params, app::DefaultJointConfig(),
                                  robot_description);
      std::fprintf(stderr, "mjc sim: robot %s\n",
                   host::DescribeRobot(*described, robot_description).c_str());
    }
    if (!subject.empty()) params.interface = load(subject).interface;

    // The board's flash. A new one comes from the factory: this mjc's image installed,
    // then commissioned with --node. An existing one is taken as it is: its image
    // (which may be none, after a power cut during an update: the bootloader then
    // stays) and its node id.
    struct stat st {};
    const bool fresh =
        flash_path.empty() || ::stat(flash_path.c_str(), &st) != 0 || st.st_size == 0;
    hal::SimFlash flash(sim::kBoardFlashPages, flash_path, &why);
    if (!why.empty()) {
      throw Failure(why +
                    " (not a simulated board's flash: an older mjc sim's? use a "
                    "new file)");
    }
    if (fresh) {
      const auto image = sim::StandInImage(build::kCommit, build::kDirty,
                                           build::kCommitTimeUnix, build::kDescribe);
      if (!sim::InstallImage(flash, image)) throw Failure("cannot install the image");
      std::fprintf(stderr, "mjc sim: a new board%s%s: image %s installed\n",
                   flash_path.empty() ? "" : " in ", flash_path.c_str(),
                   host::BuildName(build::kCommit, build::kDirty).c_str());
    }
    boot::IdentityStore identity(&flash, boot::kG474Layout.identity_page_a,
                                 boot::kG474Layout.identity_page_b);
    if (const auto record = identity.Load()) {
      if (node_option->count() > 0 && record->identity.node != node) {
        throw Failure(Exit::kUsage,
                      "--node " + std::to_string(node) + ": the board in " + flash_path +
                          " is node " + std::to_string(record->identity.node) +
                          " (its identity record, which updates keep): leave --node out "
                          "or give " +
                          std::to_string(record->identity.node));
      }
      node = record->identity.node;
    } else if (identity.Save(
                   {static_cast<std::uint8_t>(node), sim::kDefaultHardwareRevision}) !=
               boot::IdentityResult::kOk) {
      throw Failure("cannot write the board's identity record");
    } else if (!fresh) {
      std::fprintf(stderr,
                   "mjc sim: %s had no identity record: commissioned as node %d\n",
                   flash_path.c_str(), node);
    }

    sim::BootingBoardConfig board_config;
    board_config.app = {
        app::DefaultJointConfig(), {}, sim::kCalibrationPageA, sim::kCalibrationPageB};
    app::CanNodeConfig& node_config = board_config.app.can;
    node_config.node = static_cast<std::uint8_t>(node);
    // A host's heartbeats come every 100 ms of wall time, `speed` times as much board
    // time: the board's supervision timeout scales with it, so it still means 300 ms of
    // wall time, and is off at speed 0, where wall time means nothing to the board.
    node_config.host_timeout_ms =
        speed == 0 ? std::uint16_t{0}
                   : static_cast<std::uint16_t>(std::clamp(
                         std::lround(node_config.host_timeout_ms * speed), 1L, 60000L));
    // The bootloader is this build's (the host runs the logic it was compiled with).
    board_config.bootloader_build = build::kCommit;
    board_config.bootloader_dirty = build::kDirty;
    board_config.instance = InstanceFor(flash_path);
    board_config.ram_seed = std::random_device{}();
    // The board's CAN controller is the link: its error frames stand for the
    // controller's own (a bus-off report is the driver's bus-off interrupt).
    sim::LinkCanPort port(link.get());
    sim::BootingBoard board(params, board_config, &port, &flash);
    // The controller's acceptance filters, as the chip's images set them: the
    // bootloader takes its node's BootHold, BootCommand and ISO-TP channel only (it
    // then wakes for nothing else while it waits for a frame); the application, as
    // mjc sim always has, every frame (it counts the others' as ignored).
    const auto filter = [&](bool application) {
      std::vector<host::IdFilter> only;
      if (!application) {
        for (const protocol::Function f :
             {protocol::Function::kBootHold, protocol::Function::kBootCommand,
              protocol::Function::kBootIsoTpToBoard}) {
          only.push_back(
              {protocol::MakeId(static_cast<std::uint8_t>(f), board.node()), 0x7FF});
        }
      }
      if (!link->SetFilters(only, &why)) throw Failure(why);
    };
    const auto tell = [&] {
      for (sim::BoardEvent e; board.TakeEvent(&e);) {
        Tell(e, iface, robot, subject);
      }
    };
    const std::atomic<bool>& stop = StopOnSignals();
    std::signal(SIGUSR1, OnSensorFaultSignal);
    std::signal(SIGUSR2, OnSensorFaultSignal);
    const double period = board.tick_period_s();
    std::uint64_t ticks = 0;  // board time since power-on, over every reset
    // Pacing: tick n is due at origin + n·period/pace. A board that falls behind (a
    // loaded machine) does not race to catch up, which would crowd a burst of its time
    // between two of a host's heartbeats; it moves its origin instead and says so. The
    // bootloader keeps real time at --speed 0 (its hold window and its ISO-TP timeout
    // are about a host's frames).
    using Clock = std::chrono::steady_clock;
    const auto started = Clock::now();
    auto origin = started;
    std::uint64_t origin_tick = 0;
    bool in_application = board.in_application();
    filter(in_application);
    // Told once the filters are the running image's: a script that starts talking to the
    // board on "node N on IFACE" never sends into the bootloader's filters.
    tell();
    double lost_s = 0;  // wall time the board fell behind its speed, in all
    bool warned = false;
    std::uint32_t bus_off_seen = 0;
    std::uint32_t downs_said = 0;  // the interface going down, said
    bool up_said = true;
    while (!stop && (seconds == 0 || static_cast<double>(ticks) * period < seconds)) {
      // The main loop's pass once a millisecond of board time: under emulation each
      // read of the socket is a system call, and reading it every 100 µs tick cost
      // more than the plant (41 % of a QEMU TCG vCPU for a board at speed 1, half of
      // it in the kernel). A frame waits at most 1 ms.
      if (ticks % kPollEveryTicks == 0) {
        // NRST pulled low since the last pass (an edge event, so a pulse shorter than a
        // pass is not missed): the board is held in reset until it is released, then
        // starts anew; the pacing starts anew after it.
        std::string nrst_why;
        if (nrst && nrst->WaitActive(std::chrono::milliseconds(0), &nrst_why) ==
                        gpio::WaitResult::kEdge) {
          for (int level; (level = nrst->Active(&nrst_why)) != 0;) {
            if (level < 0 || stop) break;
            std::this_thread::sleep_for(std::chrono::milliseconds(1));
          }
          board.PinReset();
          origin = Clock::now();
          origin_tick = ticks;
        }
        if (!nrst_why.empty()) throw Failure("reset line: " + nrst_why);
        board.Poll();
        if (port.failed()) throw Failure(port.error());
        // An interface taken down and up again (ip link set ... down): the board rides
        // through it without its bus, as a real one whose cable is pulled; a motion
        // stops on its host timeout (fault 302).
        // Counted, not sampled: a slow board can take the kernel's report and its
        // first frame through again within one pass.
        if (port.times_down() != downs_said) {
          downs_said = port.times_down();
          up_said = false;
          std::fprintf(
              stderr,
              "mjc sim: %s went down at %.4f s: the board goes on without its bus\n",
              iface.c_str(), static_cast<double>(ticks) * period);
        }
        if (!up_said && !port.down()) {
          up_said = true;
          std::fprintf(stderr, "mjc sim: %s is up again at %.4f s\n", iface.c_str(),
                       static_cast<double>(ticks) * period);
        }
        if (board.in_application() != in_application) {
          // Another image, another pace (at --speed 0), and the counters start anew.
          in_application = board.in_application();
          filter(in_application);
          origin = Clock::now();
          origin_tick = ticks;
          bus_off_seen = 0;
        }
        // After the filters follow the image (see above).
        tell();
        if (app::JointBoard* a = board.application()) {
          for (; bus_off_seen < a->node().counters().bus_off; ++bus_off_seen) {
            std::fprintf(stderr,
                         "mjc sim: %s: bus-off at %.4f s: motor stopped (fault 303) "
                         "until the host clears it\n",
                         iface.c_str(), static_cast<double>(ticks) * period);
          }
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
      const double pace = speed > 0 ? speed : (in_application ? 0.0 : 1.0);
      if (pace > 0 && ticks % kPollEveryTicks == 0) {
        const auto due =
            origin +
            std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(
                static_cast<double>(ticks - origin_tick) * period / pace));
        const auto now = Clock::now();
        if (now - due > kMostLead) {
          lost_s += std::chrono::duration<double>(now - due).count();
          origin = now;
          origin_tick = ticks;
          if (!warned && in_application) {
            warned = true;
            std::fprintf(
                stderr,
                "mjc sim: cannot keep --speed %g on this machine: the board runs "
                "at its own slower pace (the summary says how slow)\n",
                speed);
          }
        } else if (due - now > kMostLead) {
          // Waits only once 20 ms of lead have built up: in a virtual machine (QEMU
          // TCG) sleeping and waking cost more than simulating — a board at speed 1
          // took 41 % of a vCPU sleeping every tick, 25 % every 5 ms, 19 % every 20 ms.
          // The application's frames wait at most that long (its host's heartbeat comes
          // every 100 ms); the bootloader, with nothing to do but answer, is woken by the
          // first frame.
          if (in_application) {
            std::this_thread::sleep_until(due);
          } else {
            port.WaitForFrame(static_cast<int>(
                std::chrono::ceil<std::chrono::milliseconds>(due - now).count()));
          }
        }
      }
    }
    const double simulated_s = static_cast<double>(ticks) * period;
    const double wall_s = std::chrono::duration<double>(Clock::now() - started).count();
    if (speed > 0) {
      std::fprintf(stderr, "mjc sim: speed %.2f of %g asked (%.1f s behind in all)\n",
                   wall_s > 0 ? simulated_s / wall_s : 0.0, speed, lost_s);
    }
    app::JointBoard* a = board.application();
    if (a == nullptr) {
      const boot::Bootloader* b = board.bootloader();
      protocol::BootStatus status;
      status.state = b->state();
      status.reason = b->reason();
      status.error = b->error();
      status.progress_permille = b->progress_permille();
      std::fprintf(stderr,
                   "mjc sim: %.1f s simulated, %u resets; in its bootloader (%s); frames "
                   "sent %llu (send failures %llu), rx dropped %llu, bootloader dropped "
                   "%u\n",
                   simulated_s, board.resets(), host::DescribeBootStatus(status).c_str(),
                   static_cast<unsigned long long>(link->stats().sent),
                   static_cast<unsigned long long>(link->stats().tx_failed),
                   static_cast<unsigned long long>(link->stats().rx_dropped),
                   b->frames_dropped());
      return;
    }
    // What reached the socket before the stop is the board's to account for: a
    // sender that has finished has put all of it there.
    for (protocol::CanFrame f; port.Receive(&f);) a->node().HandleFrame(f);
    const app::CanNodeCounters c = a->node().counters();
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
