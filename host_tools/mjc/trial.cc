// mjc trial: the paper's protocols against a board on the bus. "repeatability": N
// trials of five repetitions at one amplitude (--pause waits for Enter between trials,
// to re-don); "amplitude": five repetitions at each amplitude. The board estimates and
// integrates; this reports the middle three flexions of every trial: tables on stdout,
// every window in windows.csv (rewritten after each trial, so a later failure loses
// nothing), a figure (gnuplot) in the output folder.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "commands.h"
#include "mjc/host/trial_report.h"
#include "mjc/host/trial_runner.h"
#include "mjc/host/units.h"

namespace mjc::cli {
namespace {

Exit ExitOf(host::TrialEnd end) {
  switch (end) {
    case host::TrialEnd::kCompleted:
      return Exit::kOk;
    case host::TrialEnd::kLinkFailed:
      return Exit::kFailure;
    case host::TrialEnd::kNoAnswer:
      return Exit::kNoAnswer;
    case host::TrialEnd::kRefused:
      return Exit::kRefused;
    case host::TrialEnd::kFaulted:
      return Exit::kFaulted;
    case host::TrialEnd::kInterrupted:
    case host::TrialEnd::kStopped:
      return Exit::kStopped;
  }
  return Exit::kFailure;
}

}  // namespace

void AddTrial(CLI::App& app) {
  auto* cmd =
      app.add_subcommand("trial", "Run the paper's repeatability or amplitude protocol");
  static std::string iface, protocol_name = "repeatability", out_dir = "out/trial";
  static int node = 1, trials = 5, reps = 5;
  static double amplitude_deg = 25, frequency_hz = 0.5, rest_s = 1.5;
  static std::vector<double> amplitudes = {6, 8, 11, 15, 20, 25};
  static bool pause = false, figure = true;
  AddIfaceOption(cmd, &iface);
  AddNodeOption(cmd, &node);
  cmd->add_option("--protocol", protocol_name, "repeatability or amplitude")
      ->check(CLI::IsMember({"repeatability", "amplitude"}))
      ->capture_default_str();
  cmd->add_option("--trials", trials, "Repeatability: number of trials")
      ->check(CLI::Range(1, 50))
      ->capture_default_str();
  cmd->add_option("--reps", reps, "Repetitions per trial")
      ->check(CLI::Range(3, 50))
      ->capture_default_str();
  cmd->add_option("--amplitude-deg", amplitude_deg, "Repeatability: amplitude")
      ->check(CLI::Range(1.0, 90.0))
      ->capture_default_str();
  cmd->add_option("--amplitudes", amplitudes, "Amplitude protocol: amplitudes (deg)")
      ->check(CLI::Range(1.0, 90.0))
      ->capture_default_str();
  cmd->add_option("--frequency-hz", frequency_hz, "Sine frequency")
      ->check(CLI::Range(kMinFrequencyHz, kMaxFrequencyHz))
      ->capture_default_str();
  cmd->add_option("--rest-s", rest_s, "Rest before and after each trial")
      ->check(CLI::Range(0.0, 25.0))
      ->capture_default_str();
  cmd->add_flag("--pause", pause, "Wait for Enter between trials (re-donning)");
  cmd->add_option("--out", out_dir, "Output folder")->capture_default_str();
  cmd->add_flag("!--no-figure", figure, "Tables and windows.csv only (no gnuplot)");
  cmd->callback([] {
    // The output folder first: an unwritable one is found before the trials run.
    std::filesystem::create_directories(out_dir);
    std::vector<host::TrialWindows> runs;
    host::WriteWindowsCsv(runs, out_dir);
    auto link = OpenLink(iface);
    // Heartbeats flow while a trial runs: if this tool dies, the board stops it. The
    // --pause prompt waits with the board at rest, where their absence is harmless.
    host::BoardClient board(link.get(), static_cast<std::uint8_t>(node),
                            host::HostHeartbeats::kSend);
    SayBusOff(board, "mjc trial", iface);
    // Ctrl-C (or SIGTERM, SIGHUP) ends the waits: the motion is stopped and every
    // window that arrived is kept.
    const std::atomic<bool>& interrupted = StopOnSignals();
    board.SetInterrupt(&interrupted);
    const std::string saved = out_dir + "/windows.csv";
    const bool repeatability = protocol_name == "repeatability";
    const std::vector<double> plan =
        repeatability
            ? std::vector<double>(static_cast<std::size_t>(trials), amplitude_deg)
            : amplitudes;
    for (std::size_t t = 0; t < plan.size(); ++t) {
      if (pause && t > 0) {
        std::fprintf(stderr, "re-don, then press Enter for trial %zu/%zu\n", t + 1,
                     plan.size());
        std::string line;
        std::getline(std::cin, line);
        if (interrupted) {
          throw Failure(Exit::kStopped, "interrupted before trial " +
                                            std::to_string(t + 1) + " (node " +
                                            std::to_string(node) +
                                            " at rest); earlier trials are in " + saved);
        }
      }
      protocol::TrialConfig config;
      config.amplitude = Angle::Quantize(host::DegToRad(plan[t]));
      config.frequency_mHz = static_cast<std::uint16_t>(std::lround(frequency_hz * 1000));
      config.repetitions = static_cast<std::uint8_t>(reps);
      config.rest_100ms = static_cast<std::uint8_t>(std::lround(rest_s * 10));
      const std::uint64_t broken_before = board.incomplete_windows();
      const auto trial =
          host::RunBoardTrial(board, config, [&](const host::BoardWindow& w) {
            std::fprintf(stderr, "\r[trial %zu/%zu, %.0f°] repetition %u/%d %s   ", t + 1,
                         plan.size(), plan[t], w.repetition + 1, reps,
                         w.motion == Motion::kFlexion ? "flexion" : "extension");
          });
      std::fputc('\n', stderr);
      if (!trial.completed) {
        // The motor first: a file can wait, a finger should not.
        const std::string stopped =
            trial.end == host::TrialEnd::kInterrupted ? StopMotion(board) : "";
        // What arrived is kept, the interrupted trial's windows included.
        if (!trial.windows.empty()) {
          runs.push_back({plan[t], static_cast<std::uint16_t>(reps), trial.windows});
          host::WriteWindowsCsv(runs, out_dir);
        }
        std::size_t windows = 0;
        for (const host::TrialWindows& r : runs) windows += r.windows.size();
        const std::string kept = std::to_string(windows) + " windows saved to " + saved;
        if (trial.end == host::TrialEnd::kInterrupted) {
          throw Failure(Exit::kStopped, "interrupted: " + stopped + "; " + kept);
        }
        throw Failure(ExitOf(trial.end), "node " + std::to_string(node) + ", trial " +
                                             std::to_string(t + 1) + ": " + trial.error +
                                             "; " + kept);
      }
      // A flexion and an extension window a repetition: fewer means some were lost on
      // the bus (the tables then use those that arrived).
      const auto expected = 2 * static_cast<std::size_t>(reps);
      if (trial.windows.size() != expected) {
        std::fprintf(
            stderr,
            "mjc trial: trial %zu: %zu of %zu windows arrived (%llu lost a part "
            "on the bus)\n",
            t + 1, trial.windows.size(), expected,
            static_cast<unsigned long long>(board.incomplete_windows() - broken_before));
      }
      runs.push_back({plan[t], static_cast<std::uint16_t>(reps), trial.windows});
      host::WriteWindowsCsv(runs, out_dir);
    }
    std::fputs(host::TrialTables(runs, repeatability).c_str(), stdout);
    std::printf("windows: %s/windows.csv\n", out_dir.c_str());
    std::string why;
    if (!figure) return;
    if (!host::PlotTrials(out_dir, repeatability, &why)) {
      throw Failure("no figure: " + why + " (the tables and windows.csv are saved)");
    }
    std::printf("figure: %s/eta.png\n", out_dir.c_str());
  });
}

}  // namespace mjc::cli
