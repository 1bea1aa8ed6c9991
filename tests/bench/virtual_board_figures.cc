// The virtual joint board end to end over Debian's CAN stack, for ./bench (run inside
// the kernel's VM by scripts/kernel-vm, on its vcan0). The board — the image's own
// start-up, drivers and application on the STM32G474 register models (mjc_g474_board) —
// is on vcan0 through a raw socket of its own, keeping real time as in a lab; the host
// library talks to it through another, as mjc calibrate and mjc trial do, and uploads
// the calibration through the kernel's ISO-TP. Everything is judged against the plant's
// ground truth (tests/sim/virtual_board_rig.h):
//
//   virtual_board_calib_err_deg          max |ĉ − c| of c_r, c_l after the paper's
//                                        sweep on the robot alone (30°, 0.5 Hz, 10
//                                        cycles)
//   virtual_board_window_energy_err_pct  the worst analysed flexion of a 15° 0.5 Hz trial
//                                        on subject 1's hand (the calibration restored
//                                        from the board's flash file by a second board):
//                                        max(|ΔE_load|, |ΔE_unload|) / E_load
//   virtual_board_eta_err_pt             the worst |η_board − η_truth| there
//   virtual_board_vm_speed               board seconds per wall second it kept in the VM
//                                        (real time asked; below 1 it runs at its own
//                                        slower pace, which every wait follows)
//
// A run that produced no figure says why on stderr and exits 1; a model violation, a
// frame the kernel dropped for the host or a reset of the board is such a failure.
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <string>

#include "mjc/host/calibration_io.h"
#include "mjc/host/can_link.h"
#include "mjc/plant/params.h"
#include "virtual_board_rig.h"

namespace {

using namespace mjc;

constexpr const char* kIface = "vcan0";

[[noreturn]] void Fail(const std::string& why) {
  std::fprintf(stderr, "virtual_board_figures: %s\n", why.c_str());
  std::exit(1);
}

std::unique_ptr<host::SocketCanLink> Open() {
  std::string why;
  auto link = host::SocketCanLink::Open(kIface, &why);
  if (!link) Fail(why);
  return link;
}

g474board::VirtualBoardConfig Config(const plant::PlantParams& params,
                                     const std::string& flash_path,
                                     const std::string& description) {
  g474board::VirtualBoardConfig config;
  config.description = description;
  config.plant = params;
  config.flash_path = flash_path;
  config.speed = 1;
  config.name = "virtual_board_figures";
  config.iface = kIface;
  return config;
}

// Until the board's first heartbeat: it is on the bus.
void AwaitUp(host::BoardClient& client) {
  host::WaitEnd end{};
  std::string why;
  if (!client.Await([&] { return client.status().heard; }, {}, &end, &why)) Fail(why);
}

// What a run must not have had, checked once the board has stopped.
void CheckClean(const g474board::VirtualBoard& board, const host::CanLink& host_link,
                const char* phase) {
  const g474board::VirtualBoardSummary s = board.Summary();
  if (!s.error.empty()) Fail(std::string(phase) + ": " + s.error);
  if (s.violations > 0) {
    Fail(std::string(phase) + ": " + std::to_string(s.violations) +
         " model violation(s), the first: " + board.violations().front().source + ": " +
         board.violations().front().what);
  }
  if (s.resets > 0) Fail(std::string(phase) + ": the board was reset");
  if (host_link.stats().rx_dropped > 0) {
    Fail(std::string(phase) + ": the kernel dropped " +
         std::to_string(host_link.stats().rx_dropped) + " frames for the host");
  }
}

}  // namespace

int main() {
  const std::filesystem::path flash =
      std::filesystem::temp_directory_path() /
      ("virtual_board_figures_" + std::to_string(::getpid()) + ".flash");
  std::filesystem::remove(flash);
  double simulated_s = 0, wall_s = 0;

  // The robot alone: the paper's sweep, the fit, the upload through the kernel's ISO-TP.
  const plant::PlantParams robot = plant::LoadPlantParams("default");
  g474board::rig::CalibrationRun cal;
  {
    auto board_link = Open();
    auto host_link = Open();
    g474board::VirtualBoard board(Config(robot, flash.string(), "default, robot alone"),
                                  board_link.get());
    board.Resume();
    host::BoardClient client(host_link.get(), 1);
    AwaitUp(client);
    cal = g474board::rig::SweepAndFit(client, g474board::rig::PaperSweep(), robot);
    if (!cal.error.empty()) Fail("calibration: " + cal.error);
    std::string why;
    const host::UploadOutcome sent =
        host::UploadCalibration(kIface, 1, cal.record, 1000, &why);
    if (sent.status != host::UploadStatus::kAnswered) Fail("upload: " + why);
    if (sent.result != protocol::CalibrationResult::kAccepted) {
      Fail("the board refused the calibration");
    }
    board.Stop();
    CheckClean(board, *host_link, "calibration");
    simulated_s += board.Summary().simulated_s;
    wall_s += board.Summary().wall_s;
  }

  // Subject 1's hand donned: the board restores the calibration from its flash file.
  plant::PlantParams donned = robot;
  donned.interface = plant::LoadPlantParams("subject1").interface;
  auto board_link = Open();
  auto host_link = Open();
  g474board::VirtualBoard board(
      Config(donned, flash.string(), "default, subject1 donned"), board_link.get());
  const g474board::rig::EnergyTruth truth(board);
  board.Resume();
  host::BoardClient client(host_link.get(), 1);
  AwaitUp(client);
  const g474board::rig::TrialRun trial =
      g474board::rig::RunTrialAgainstTruth(client, truth, g474board::rig::JudgedTrial());
  board.Stop();
  if (!trial.error.empty()) Fail("trial: " + trial.error);
  CheckClean(board, *host_link, "trial");
  simulated_s += board.Summary().simulated_s;
  wall_s += board.Summary().wall_s;
  std::filesystem::remove(flash);

  std::printf("virtual_board_calib_err_deg: %.4f deg\n", cal.worst_error_deg());
  std::printf("virtual_board_window_energy_err_pct: %.2f %%\n",
              trial.worst_energy_error_pct());
  std::printf("virtual_board_eta_err_pt: %.2f points\n", trial.worst_eta_error_pt());
  std::printf("virtual_board_vm_speed: %.2f x (board s per wall s, real time asked)\n",
              wall_s > 0 ? simulated_s / wall_s : 0.0);
  return 0;
}
