// mjc-g474: the joint board's firmware — the image's own start-up, drivers and
// application — on a virtual STM32G474 (the register models of sim_host/g474), bound to
// the simulated plant and to a CAN interface. Same options and messages as `mjc sim`,
// so scripts and tools use either: "mjc-g474: node N on vcan0 (...)" once the board is
// up, the same summary line at the end. Exit status 1 when the models saw a rule of the
// manual broken (each printed once as it happened), or on a failure on this side.
#include <csignal>
#include <cstdio>
#include <exception>
#include <random>
#include <string>
#include <string_view>

#include "commands.h"
#include "mjc/g474board/virtual_board.h"
#include "mjc/host/config.h"
#include "mjc/plant/params.h"

namespace {

using mjc::cli::Exit;

// SIGUSR1 raises the joint encoder's error flag until SIGUSR2 clears it (as mjc sim).
mjc::g474board::VirtualBoard* g_board = nullptr;
void OnSensorFaultSignal(int signal) {
  if (g_board != nullptr) g_board->SetJointError(signal == SIGUSR1);
}

mjc::plant::PlantParams Load(const std::string& s) {
  return s.find('/') != std::string::npos || s.ends_with(".json")
             ? mjc::plant::LoadPlantParamsFile(s)
             : mjc::plant::LoadPlantParams(s);
}

int Run(const std::string& iface, int node, const std::string& robot,
        const std::string& subject, const std::string& flash_path, double speed,
        double seconds) {
  auto link = mjc::cli::OpenLink(iface);
  mjc::g474board::VirtualBoardConfig config;
  config.plant = Load(robot);
  if (!subject.empty()) config.plant.interface = Load(subject).interface;
  config.node = static_cast<std::uint8_t>(node);
  config.flash_path = flash_path;
  // Each run a chip of its own, as mjc sim draws its board's instance: two virtual
  // boards on one bus tell themselves apart (BoardInfo::instance, from the unique ID).
  std::random_device entropy;
  for (auto& word : config.unique_id) word = entropy();
  config.speed = speed;
  config.seconds = seconds;
  config.stop = &mjc::cli::StopOnSignals();
  config.iface = iface;
  config.description =
      robot + (subject.empty() ? ", robot alone" : ", " + subject + " donned");

  mjc::g474board::VirtualBoard board(config, link.get());
  g_board = &board;
  std::signal(SIGUSR1, OnSensorFaultSignal);
  std::signal(SIGUSR2, OnSensorFaultSignal);
  board.Resume();
  board.Wait();
  std::signal(SIGUSR1, SIG_DFL);
  std::signal(SIGUSR2, SIG_DFL);
  g_board = nullptr;

  const mjc::g474board::VirtualBoardSummary s = board.Summary();
  if (speed > 0) {
    std::fprintf(stderr, "mjc-g474: speed %.2f of %g asked (%.1f s behind in all)\n",
                 s.wall_s > 0 ? s.simulated_s / s.wall_s : 0.0, speed, s.behind_s);
  }
  std::fprintf(stderr, "mjc-g474: %s\n", board.SummaryLine().c_str());
  if (!s.error.empty()) throw mjc::cli::Failure(s.error);
  if (s.violations > 0) {
    std::fprintf(stderr,
                 "mjc-g474: %zu model violation(s): the firmware broke a rule of the "
                 "manual (each printed above when it first happened)\n",
                 s.violations);
    return static_cast<int>(Exit::kFailure);
  }
  return static_cast<int>(Exit::kOk);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "mjc-g474: the joint board's firmware on a virtual STM32G474 (register models), "
      "bound to the simulated plant and a CAN interface"};
  app.footer(
      "Signals: SIGUSR1 makes the joint encoder flag an error (fault 101) until "
      "SIGUSR2. A bus-off error frame on the interface is taken as the board's own "
      "bus-off. Exit status: 0 done; 1 a model saw a rule of the manual broken, or a "
      "failure on this side (interface, files); 2 bad command line.");
  std::string why;
  // mjc's defaults (its config file, MJC_IFACE): --iface and --node default as mjc sim's.
  if (!mjc::cli::LoadDefaults(argc, argv, &why)) {
    std::fprintf(stderr, "mjc-g474: %s\n", why.c_str());
    return static_cast<int>(Exit::kFailure);
  }
  std::string iface, robot = "default", subject, flash_path;
  int node = 1;
  double seconds = 0, speed = 1;
  mjc::cli::AddIfaceOption(&app, &iface);
  mjc::cli::AddNodeOption(
      &app, &node, "Node id, when the flash holds no identity record (a record's wins)",
      false);
  app.add_option("--robot", robot, "Plant parameter set of the robot (name or .json)")
      ->capture_default_str();
  app.add_option("--subject", subject,
                 "Don this subject's interface (name or .json); none: robot alone");
  app.add_option("--seconds", seconds,
                 "Stop after this much simulated time (0: until SIGINT/SIGTERM)")
      ->check(CLI::NonNegativeNumber);
  app.add_option(
      "--flash", flash_path,
      "Keep the chip's flash (the stored calibration) in this file across runs");
  app.add_option("--speed", speed,
                 "Simulated seconds per wall second (0: as fast as possible)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  // One line, as mjc's: "mjc-g474: --node: 0 is outside 1..8 (see mjc-g474 --help)".
  app.failure_message([](const CLI::App*, const CLI::Error& e) {
    return std::string("mjc-g474: ") + e.what() + " (see mjc-g474 --help)\n";
  });
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : static_cast<int>(Exit::kUsage);
  }
  try {
    return Run(iface, node, robot, subject, flash_path, speed, seconds);
  } catch (const mjc::cli::Failure& e) {
    std::fprintf(stderr, "mjc-g474: %s\n", e.what());
    return static_cast<int>(e.exit());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "mjc-g474: %s\n", e.what());
    return static_cast<int>(Exit::kFailure);
  }
}
