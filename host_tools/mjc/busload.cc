// mjc busload: the worst-case bus load of N boards at the board's default rates.
#include "mjc/host/busload.h"

#include <cstdio>

#include "commands.h"

namespace mjc::cli {

void AddBusload(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "busload", "Worst-case CAN bus load of N boards at the board's default rates");
  static int boards = 8;
  static double nominal_kbps = 1000, data_kbps = 5000;
  cmd->add_option("--boards", boards, "Number of boards")
      ->check(CLI::Range(1, int{protocol::kMaxNode} - int{protocol::kMinNode} + 1))
      ->capture_default_str();
  cmd->add_option("--nominal-kbps", nominal_kbps, "Nominal (arbitration) bit rate")
      ->check(CLI::Range(10.0, 1000.0))
      ->capture_default_str();
  cmd->add_option("--data-kbps", data_kbps, "CAN FD data bit rate")
      ->check(CLI::Range(10.0, 8000.0))
      ->capture_default_str();
  static bool figures = false;
  cmd->add_flag("--figures", figures,
                "Print ./bench's figures instead (8 boards, 1 and 5 Mbit/s), one "
                "'name: value unit' line each")
      ->excludes("--boards", "--nominal-kbps", "--data-kbps");
  cmd->callback([] {
    std::fputs(
        figures
            ? host::BusLoadFigures().c_str()
            : host::BusLoadReport(boards, nominal_kbps * 1e3, data_kbps * 1e3).c_str(),
        stdout);
  });
}

}  // namespace mjc::cli
