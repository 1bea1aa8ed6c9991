#include "mjc/host/busload.h"

#include <cstdio>

#include "commands.h"

namespace mjc::cli {

void AddBusload(CLI::App& app, int* status) {
  auto* cmd = app.add_subcommand(
      "busload", "Worst-case CAN bus load of N boards at the board's default rates");
  static int boards = 8;
  static double nominal_kbps = 1000, data_kbps = 5000;
  cmd->add_option("--boards", boards, "Number of boards")
      ->check(CLI::Range(1, 8))
      ->capture_default_str();
  cmd->add_option("--nominal-kbps", nominal_kbps, "Nominal (arbitration) bit rate")
      ->check(CLI::Range(10.0, 1000.0))
      ->capture_default_str();
  cmd->add_option("--data-kbps", data_kbps, "CAN FD data bit rate")
      ->check(CLI::Range(10.0, 8000.0))
      ->capture_default_str();
  cmd->callback([status] {
    const app::CanNodeConfig defaults;
    const host::BusTiming fd{true, nominal_kbps * 1e3, data_kbps * 1e3};
    const host::BusTiming classic{false, nominal_kbps * 1e3, nominal_kbps * 1e3};
    std::fputs(
        host::FormatBusLoad(host::ComputeBusLoad(defaults, boards, fd, 0), fd, boards)
            .c_str(),
        stdout);
    std::fputs(host::FormatBusLoad(host::ComputeBusLoad(defaults, boards, classic, 0),
                                   classic, boards)
                   .c_str(),
               stdout);
    std::printf(
        "highest angle-telemetry rate within 50%%: FD %.0f Hz, classical %.0f Hz\n",
        host::MaxTelemetryHz(defaults, boards, fd, 0.5),
        host::MaxTelemetryHz(defaults, boards, classic, 0.5));
    *status = 0;
  });
}

}  // namespace mjc::cli
