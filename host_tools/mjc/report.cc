// mjc report: re-renders the tables and figure of a trial run from the folder mjc trial
// wrote: its run.json says the protocol (and the board, the subject, how the run
// ended), its windows.csv the windows. A folder from before run.json has the protocol
// guessed from its windows.csv, and says so.
#include "mjc/host/report.h"

#include <cstdio>
#include <filesystem>

#include "commands.h"
#include "mjc/host/describe.h"
#include "mjc/host/run_record.h"
#include "mjc/host/trial_report.h"

namespace mjc::cli {

void AddReport(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "report", "Tables and figure of a trial run (its run.json and windows.csv)");
  static std::string dir, protocol_name;
  static bool figure = true;
  cmd->add_option("dir", dir, "The output folder of mjc trial")
      ->required()
      ->check(CLI::ExistingDirectory);
  cmd->add_option("--protocol", protocol_name,
                  "repeatability or amplitude, for a folder without run.json (default: "
                  "amplitude when the trials' amplitudes differ, else repeatability)")
      ->check(CLI::IsMember({"repeatability", "amplitude"}));
  cmd->add_flag("!--no-figure", figure, "Tables only (no gnuplot)");
  cmd->callback([] {
    std::string why;
    const auto run = host::ReadRunRecord(dir, &why);
    if (!run && !why.empty()) throw Failure(why);
    if (run && run->command != "trial") {
      throw Failure(dir + "/run.json is a " + run->command + " run's, not a trial's");
    }
    int version = 0;
    const auto trials = host::ReadWindowsCsv(dir, &why, &version);
    if (!trials) throw Failure(why);
    const bool same_amplitude = host::SameAmplitude(*trials);
    bool repeatability = false;
    std::string header;
    if (run) {
      repeatability = run->protocol == "repeatability";
      if (!protocol_name.empty() && protocol_name != run->protocol) {
        throw Failure("--protocol " + protocol_name + ", but " + dir +
                      "/run.json says the run was " + run->protocol);
      }
      header = "Node " + std::to_string(run->node) + " on " + run->iface + ", board " +
               (run->board ? host::BuildName(run->board->build, run->board->dirty)
                           : std::string("of unknown build")) +
               (run->subject ? ", subject " + *run->subject : "") + "; " + run->protocol +
               " protocol, started " + run->started_utc + " on " + run->host + " (mjc " +
               run->mjc + ").\n";
      // What windows.csv holds must be what run.json planned: a file copied from
      // another run, or edited, is refused naming the trial.
      for (std::size_t t = 0; t < trials->size(); ++t) {
        const host::TrialWindows& got = (*trials)[t];
        const std::string trial = "windows.csv's trial " + std::to_string(t + 1);
        if (t >= run->amplitudes_deg.size()) {
          throw Failure(dir + ": " + trial + " is beyond the " +
                        std::to_string(run->amplitudes_deg.size()) +
                        " trials run.json planned");
        }
        // Both files write %.9g of the same double.
        if (host::CsvTable::Number(got.amplitude_deg) !=
            host::CsvTable::Number(run->amplitudes_deg[t])) {
          throw Failure(dir + ": " + trial + " ran at " +
                        host::CsvTable::Number(got.amplitude_deg) +
                        "°, but run.json says " +
                        host::CsvTable::Number(run->amplitudes_deg[t]) + "°");
        }
        if (got.repetitions != run->repetitions) {
          throw Failure(dir + ": " + trial + " has " + std::to_string(got.repetitions) +
                        " repetitions, but run.json says " +
                        std::to_string(run->repetitions));
        }
      }
      std::size_t windows = 0;
      for (const host::TrialWindows& t : *trials) windows += t.windows.size();
      if (run->end.outcome == "running" && host::RunStillGoing(*run)) {
        header += "The run is still going (pid " + std::to_string(*run->pid) +
                  "): the tables hold the " + std::to_string(windows) +
                  " windows so far.\n";
      } else if (run->end.outcome == "running") {
        // run.json was never told how the run ended: the process died (SIGKILL, a
        // crash, a power cut) with every window it had received in windows.csv.
        const std::string stopped =
            "the host stopped after " + std::to_string(windows) +
            " windows without a word (killed, crashed or powered off): run.json still "
            "says \"running\"";
        header +=
            "The run did not complete: " + stopped + "; the tables hold what arrived.\n";
        std::fprintf(stderr, "mjc report: %s\n", stopped.c_str());
      } else if (run->end.outcome != "completed") {
        header += "The run did not complete: " + run->end.outcome +
                  (run->end.message.empty() ? "" : " (" + run->end.message + ")") +
                  "; the tables hold what arrived.\n";
      }
    } else {
      if (protocol_name == "repeatability" && !same_amplitude) {
        throw Failure(
            "--protocol repeatability, but the trials in windows.csv differ in "
            "amplitude");
      }
      repeatability =
          protocol_name.empty() ? same_amplitude : protocol_name == "repeatability";
      header =
          std::string("No run.json (written by an mjc before it): the protocol is ") +
          (protocol_name.empty()
               ? "guessed from windows.csv (" +
                     std::string(same_amplitude ? "one amplitude"
                                                : "the amplitudes differ") +
                     ")"
               : "as --protocol says") +
          ": " + (repeatability ? "repeatability" : "amplitude") + ".\n";
      std::fprintf(stderr, "mjc report: %s", header.c_str());
    }
    if (version == 1) {
      header += "windows.csv is version 1 (repetitions counted from 0 in the file).\n";
    }
    const std::string tables = host::TrialTables(*trials, repeatability);
    std::fputs(tables.c_str(), stdout);
    host::WriteFile(std::filesystem::path(dir) / "report.md",
                    "# Trial report\n\n" + header + "\n" + tables);
    std::printf("report: %s/report.md\n", dir.c_str());
    if (!figure) return;
    host::RunRecord untitled;
    untitled.protocol = repeatability ? "repeatability" : "amplitude";
    const std::string title =
        run ? host::RunTitle(*run)
            : "Energy loss per flexion: " + untitled.protocol + " protocol (" + dir + ")";
    // A version 1 file is plotted from a version 2 copy beside it (the original is
    // left as it was).
    std::string data = "windows.csv";
    if (version == 1) {
      data = "windows.v2.csv";
      std::filesystem::create_directories(std::filesystem::path(dir) / ".v2");
      host::WriteWindowsCsv(*trials, std::filesystem::path(dir) / ".v2");
      std::filesystem::rename(std::filesystem::path(dir) / ".v2" / "windows.csv",
                              std::filesystem::path(dir) / data);
      std::filesystem::remove(std::filesystem::path(dir) / ".v2");
    }
    if (!host::PlotTrials(dir, repeatability, title, &why, data)) {
      throw Failure("no figure: " + why + " (report.md is saved)");
    }
    std::printf("figure: %s/eta.png\n", dir.c_str());
  });
}

}  // namespace mjc::cli
