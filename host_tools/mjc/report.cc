// mjc report: re-renders the tables and figure of a trial run from the windows.csv that
// mjc trial wrote (e.g. after editing or merging runs).
#include <cstdio>
#include <fstream>

#include "commands.h"
#include "mjc/host/trial_report.h"

namespace mjc::cli {

void AddReport(CLI::App& app, int* status) {
  auto* cmd =
      app.add_subcommand("report", "Tables and figure of a trial run (its windows.csv)");
  static std::string dir;
  static int reps = 5;
  static std::string protocol_name = "repeatability";
  cmd->add_option("dir", dir, "The output folder of mjc trial")
      ->required()
      ->check(CLI::ExistingDirectory);
  cmd->add_option("--reps", reps, "Repetitions per trial (selects the middle three)")
      ->check(CLI::Range(3, 50))
      ->capture_default_str();
  cmd->add_option("--protocol", protocol_name, "repeatability or amplitude")
      ->check(CLI::IsMember({"repeatability", "amplitude"}))
      ->capture_default_str();
  cmd->callback([status] {
    std::string why;
    const auto trials = host::ReadWindowsCsv(dir, &why);
    if (!trials) {
      std::fprintf(stderr, "mjc report: %s\n", why.c_str());
      *status = 1;
      return;
    }
    const std::string tables = host::TrialTables(
        *trials, static_cast<std::uint16_t>(reps), protocol_name == "repeatability");
    std::fputs(tables.c_str(), stdout);
    std::ofstream(std::filesystem::path(dir) / "report.md") << "# Trial report\n\n"
                                                            << tables;
    if (!host::PlotTrials(dir, &why)) {
      std::fprintf(stderr, "mjc report: %s\n", why.c_str());
      *status = 1;
      return;
    }
    std::printf("report: %s/report.md, %s/eta.png\n", dir.c_str(), dir.c_str());
    *status = 0;
  });
}

}  // namespace mjc::cli
