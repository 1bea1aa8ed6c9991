// mjc-busload: the worst-case bus load of 8 boards at the board's default rates, on
// CAN FD 1/5 Mbit/s and classical 1 Mbit/s, and the highest 1 kHz-class telemetry rate
// each keeps within a 50 % budget.
#include <cstdio>

#include "mjc/host/busload.h"

int main(int argc, char** argv) {
  if (argc != 1) {
    std::fprintf(stderr, "usage: %s   (takes no arguments)\n", argv[0]);
    return 2;
  }
  using namespace mjc;
  const app::CanNodeConfig defaults;
  constexpr int kBoards = 8;
  constexpr double kSetpointHz = 0;  // trials run on the board; streaming is optional
  const host::BusTiming fd{true, 1e6, 5e6};
  const host::BusTiming classic{false, 1e6, 1e6};
  std::fputs(host::FormatBusLoad(host::ComputeBusLoad(defaults, kBoards, fd, kSetpointHz),
                                 fd, kBoards)
                 .c_str(),
             stdout);
  std::fputs(
      host::FormatBusLoad(host::ComputeBusLoad(defaults, kBoards, classic, kSetpointHz),
                          classic, kBoards)
          .c_str(),
      stdout);
  std::printf("highest angle-telemetry rate within 50%%: FD %.0f Hz, classical %.0f Hz\n",
              host::MaxTelemetryHz(defaults, kBoards, fd, 0.5),
              host::MaxTelemetryHz(defaults, kBoards, classic, 0.5));
  return 0;
}
