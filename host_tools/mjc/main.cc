// mjc: the Maestro joint boards' host tool, over SocketCAN. `mjc --help` lists the
// subcommands; each has its own --help. Bad flags, missing interfaces and silent nodes
// are reported in one line and exit non-zero.
#include <cstdio>

#include "commands.h"

int main(int argc, char** argv) {
  CLI::App app{"mjc: host tool for the Maestro exoskeleton's joint boards (SocketCAN)"};
  app.require_subcommand(1);
  int status = 0;
  mjc::cli::AddSim(app, &status);
  mjc::cli::AddLog(app, &status);
  mjc::cli::AddCal(app, &status);
  mjc::cli::AddCalibrate(app, &status);
  mjc::cli::AddBusload(app, &status);
  mjc::cli::AddTrial(app, &status);
  mjc::cli::AddReport(app, &status);
  mjc::cli::AddMonitor(app, &status);
  CLI11_PARSE(app, argc, argv);
  return status;
}
