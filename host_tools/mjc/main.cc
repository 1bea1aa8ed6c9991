// mjc: the Maestro joint boards' host tool, over SocketCAN. `mjc --help` lists the
// subcommands; each has its own --help. Every failure (bad flags, bad files, missing
// interfaces, silent nodes) is one line on stderr and a non-zero exit status
// (commands.h: Exit).
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <exception>
#include <string>

#include "commands.h"

namespace {

// "mjc cal download": the subcommands the command line chose.
std::string CommandName(const CLI::App& app) {
  std::string name = "mjc";
  for (const CLI::App* a = &app; !a->get_subcommands().empty();) {
    a = a->get_subcommands().front();
    name += " " + a->get_name();
  }
  return name;
}

int Fail(const CLI::App& app, const char* what, mjc::cli::Exit exit) {
  std::fprintf(stderr, "%s: %s\n", CommandName(app).c_str(), what);
  return static_cast<int>(exit);
}

}  // namespace

int main(int argc, char** argv) {
  using mjc::cli::Exit;
  CLI::App app{"mjc: host tool for the Maestro exoskeleton's joint boards (SocketCAN)"};
  app.footer(mjc::cli::kExitStatusHelp);  // before the subcommands: they inherit it
  app.require_subcommand(1);
  mjc::cli::AddSim(app);
  mjc::cli::AddLog(app);
  mjc::cli::AddCal(app);
  mjc::cli::AddCalibrate(app);
  mjc::cli::AddBusload(app);
  mjc::cli::AddTrial(app);
  mjc::cli::AddReport(app);
  mjc::cli::AddMonitor(app);
  mjc::cli::AddClear(app);
  mjc::cli::AddStop(app);
  // The subcommands' callbacks run inside parse().
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : static_cast<int>(Exit::kUsage);  // e.g. --help: 0
  } catch (const mjc::cli::Failure& e) {
    return Fail(app, e.what(), e.exit());
  } catch (const std::exception& e) {
    return Fail(app, e.what(), Exit::kFailure);
  }
  // Reports and tables go to stdout: a full disk or a closed pipe there is a failure.
  errno = 0;
  if (std::fflush(stdout) != 0 || std::ferror(stdout)) {
    const std::string what = std::string("error writing stdout") +
                             (errno ? ": " + std::string(std::strerror(errno)) : "");
    return Fail(app, what.c_str(), Exit::kFailure);
  }
  return static_cast<int>(Exit::kOk);
}
