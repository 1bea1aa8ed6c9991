// mjc report: re-renders the tables and figure of a trial run from the windows.csv that
// mjc trial wrote (e.g. after editing or merging runs). The repetitions of each trial
// and the protocol come from the file itself.
#include "mjc/host/report.h"

#include <cstdio>
#include <filesystem>

#include "commands.h"
#include "mjc/host/trial_report.h"

namespace mjc::cli {

void AddReport(CLI::App& app) {
  auto* cmd =
      app.add_subcommand("report", "Tables and figure of a trial run (its windows.csv)");
  static std::string dir, protocol_name;
  static bool figure = true;
  cmd->add_option("dir", dir, "The output folder of mjc trial")
      ->required()
      ->check(CLI::ExistingDirectory);
  cmd->add_option("--protocol", protocol_name,
                  "repeatability or amplitude (default: amplitude when the trials' "
                  "amplitudes differ, else repeatability)")
      ->check(CLI::IsMember({"repeatability", "amplitude"}));
  cmd->add_flag("!--no-figure", figure, "Tables only (no gnuplot)");
  cmd->callback([] {
    std::string why;
    const auto trials = host::ReadWindowsCsv(dir, &why);
    if (!trials) throw Failure(why);
    const bool same_amplitude = host::SameAmplitude(*trials);
    if (protocol_name == "repeatability" && !same_amplitude) {
      throw Failure(
          "--protocol repeatability, but the trials in windows.csv differ in amplitude");
    }
    const bool repeatability =
        protocol_name.empty() ? same_amplitude : protocol_name == "repeatability";
    const std::string tables = host::TrialTables(*trials, repeatability);
    std::fputs(tables.c_str(), stdout);
    host::WriteFile(std::filesystem::path(dir) / "report.md",
                    "# Trial report\n\n" + tables);
    std::printf("report: %s/report.md\n", dir.c_str());
    if (!figure) return;
    if (!host::PlotTrials(dir, repeatability, &why)) {
      throw Failure("no figure: " + why + " (report.md is saved)");
    }
    std::printf("figure: %s/eta.png\n", dir.c_str());
  });
}

}  // namespace mjc::cli
