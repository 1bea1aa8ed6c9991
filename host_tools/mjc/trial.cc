// mjc trial: the paper's protocols against a board on the bus. "repeatability": N
// trials of five repetitions at one amplitude (--pause waits for Enter between trials,
// to re-don); "amplitude": five repetitions at each amplitude. The board estimates and
// integrates; this reports the middle three flexions of every trial: tables on stdout,
// every window in windows.csv (appended the moment it arrives, so a host that dies
// loses at most the window in flight), run.json (the board, its calibration, the
// protocol, how the run ended; rewritten whole at each change) and a figure (gnuplot)
// in a new output folder.
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <optional>
#include <string>
#include <vector>

#include "commands.h"
#include "mjc/build_id.h"
#include "mjc/host/calibration_io.h"
#include "mjc/host/describe.h"
#include "mjc/host/joint_limits.h"
#include "mjc/host/robot_description.h"
#include "mjc/host/run_record.h"
#include "mjc/host/trial_report.h"
#include "mjc/host/trial_runner.h"
#include "mjc/host/units.h"
#include "mjc/host/window_sync.h"

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
    case host::TrialEnd::kAmbiguous:
      return Exit::kAmbiguous;
    case host::TrialEnd::kWrongConfig:
      return Exit::kRefused;
  }
  return Exit::kFailure;
}

// The files a trial run writes into its folder (replaced under --force).
const std::vector<std::string> kTrialOutputs = {
    "windows.csv", "run.json", "run.mat", "eta.png", "eta.gp", "eta.gp.log", "report.md"};

}  // namespace

void AddTrial(CLI::App& app) {
  auto* cmd =
      app.add_subcommand("trial", "Run the paper's repeatability or amplitude protocol");
  static std::string iface, protocol_name = "repeatability", subject;
  static OutputOptions output;
  static int node = 1, trials = 5, reps = 5;
  static double amplitude_deg = 25, frequency_hz = 0.5, rest_s = 1.5;
  static std::vector<double> amplitudes = {6, 8, 11, 15, 20, 25};
  static bool pause = false, figure = true;
  static EstopOptions estop_options;
  static std::string sync_name;
  static std::string robot_path;
  AddIfaceOption(cmd, &iface);
  AddNodeOption(cmd, &node);
  cmd->add_option("--protocol", protocol_name, "repeatability or amplitude")
      ->check(CLI::IsMember({"repeatability", "amplitude"}))
      ->capture_default_str();
  cmd->add_option("--trials", trials, "Repeatability: number of trials")
      ->check(InRange(1, 50))
      ->capture_default_str();
  cmd->add_option("--reps", reps, "Repetitions per trial")
      ->check(InRange(3, 50))
      ->capture_default_str();
  cmd->add_option("--amplitude-deg", amplitude_deg, "Repeatability: amplitude")
      ->check(InRange(1.0, 90.0, "°"))
      ->capture_default_str();
  cmd->add_option("--amplitudes", amplitudes, "Amplitude protocol: amplitudes (deg)")
      ->check(InRange(1.0, 90.0, "°"))
      ->capture_default_str();
  AddFrequencyOption(cmd, &frequency_hz, "Sine frequency");
  cmd->add_option("--rest-s", rest_s, "Rest before and after each trial")
      ->check(InRange(0.0, 25.0, "s"))
      ->capture_default_str();
  cmd->add_option("--subject", subject,
                  "Who wears the device (an id, recorded in run.json and the figure)");
  cmd->add_flag("--pause", pause, "Wait for Enter between trials (re-donning)");
  AddOutputOptions(cmd, &output, "out/trial");
  cmd->add_flag("!--no-figure", figure, "Tables and windows.csv only (no gnuplot)");
  AddEstopOptions(cmd, &estop_options, EstopDefault::kConfig);
  if (Defaults().sync_line) sync_name = Defaults().sync_line->text();
  cmd->add_option("--sync-line", sync_name,
                  "Trigger output CHIP:LINE for other instruments: high during flexion "
                  "windows, low during extension windows and at rest, so every window "
                  "start is an edge; none: no trigger")
      ->check(LineSpecCheck(true))
      ->capture_default_str();
  JointSuppliesRobot(
      cmd,
      cmd->add_option("--robot", robot_path,
                      "Robot description of the joint (robots/*.json): its torque and "
                      "travel limits go to the board before anything moves (with "
                      "--joint: the joint's, from the hand file; another file is "
                      "refused)"),
      &robot_path);
  cmd->callback([] {
    // The joint's description first: a bad file moves nothing and writes nothing.
    std::optional<host::RobotDescription> robot;
    if (!robot_path.empty()) {
      std::string why;
      robot = host::LoadRobotDescription(robot_path, &why);
      if (!robot) throw Failure("robot description refused: " + why);
    }
    std::error_code no_folder;
    const bool created =
        output.out.empty() || !std::filesystem::exists(output.out, no_folder);
    const std::filesystem::path dir =
        PrepareOutputs("mjc trial", output, "out/trial", kTrialOutputs);
    // Whether a board answered: a run that never reached one (no interface, a silent
    // node) leaves no folder behind; once one answered, its run.json says what it said.
    bool reached = false;
    const std::string saved = (dir / "windows.csv").string();
    // Created first: an unwritable folder is found before the trials run. Each window
    // is appended as it arrives; `runs` keeps them for the tables.
    std::optional<host::WindowsCsvWriter> csv;
    try {
      csv.emplace(dir);
    } catch (const std::exception& e) {
      throw Failure(e.what());
    }
    std::vector<host::TrialWindows> runs;
    std::string write_error;  // the first window that could not be appended
    const bool repeatability = protocol_name == "repeatability";
    const std::vector<double> plan =
        repeatability
            ? std::vector<double>(static_cast<std::size_t>(trials), amplitude_deg)
            : amplitudes;
    host::RunRecord record;
    record.command = "trial";
    record.node = node;
    record.iface = iface;
    if (!subject.empty()) record.subject = subject;
    record.protocol = protocol_name;
    record.amplitudes_deg = plan;
    record.frequency_hz = frequency_hz;
    record.repetitions = reps;
    record.rest_s = rest_s;
    record.started_utc = host::UtcNow();
    record.host = host::HostName();
    record.mjc = build::kDescribe;
    record.pid = static_cast<long>(::getpid());
    host::WriteRunRecord(record, dir);
    // Every way out of here says how the run ended in run.json, then the Failure.
    const auto end = [&](Exit exit, const std::string& what,
                         std::optional<int> fault = std::nullopt) {
      EndProgress();
      record.end.outcome = OutcomeOf(exit);
      record.end.message = what;
      record.end.fault_code = fault;
      host::WriteRunRecord(record, dir);
      if (!reached && exit != Exit::kAmbiguous) {
        host::DiscardUnstartedRun(dir, kTrialOutputs, created);
      }
      return Failure(exit, what);
    };
    // The trigger line: low (rest) from the start, back to low however the run ends.
    std::unique_ptr<gpio::OutputLine> sync_line;
    std::optional<host::WindowSync> sync;
    std::string sync_error;
    struct RestAtEnd {
      std::optional<host::WindowSync>* sync;
      ~RestAtEnd() {
        std::string ignored;
        if (*sync) (void)(*sync)->Rest(&ignored);
      }
    } rest_at_end{&sync};
    // The emergency-stop watch, from before anything moves to the end of the run.
    std::unique_ptr<host::EmergencyStopThread> estop;
    const auto stopped_by_estop = [&] { return estop && estop->triggered(); };
    // The run ended by the emergency stop: "emergency_stop" in run.json, exit 6.
    const auto estop_end = [&](const std::string& what) {
      EndProgress();
      record.end.outcome = "emergency_stop";
      record.end.message = what;
      host::WriteRunRecord(record, dir);
      if (!reached) host::DiscardUnstartedRun(dir, kTrialOutputs, created);
      return Failure(Exit::kStopped, what);
    };
    try {
      if (const auto spec = LineOf(sync_name)) {
        gpio::LineOptions options;
        options.consumer = "mjc trial sync";
        std::string why;
        sync_line = gpio::OpenOutput(*spec, options, &why);
        if (!sync_line) throw Failure("sync line: " + why);
        sync.emplace(sync_line.get());
        if (!sync->Rest(&why)) throw Failure("sync line: " + why);
      }
      auto link = OpenLink(iface);
      // Heartbeats flow while a trial runs: if this tool dies, the board stops it. The
      // --pause prompt waits with the board at rest, where their absence is harmless.
      host::BoardClient board(link.get(), static_cast<std::uint8_t>(node),
                              host::HostHeartbeats::kSend);
      // Ctrl-C (or SIGTERM, SIGHUP) ends the waits: the motion is stopped and every
      // window that arrived is kept. So does the emergency stop (after its StopAll).
      estop = GuardMotion(board, "mjc trial", iface, estop_options);
      const std::atomic<bool>& interrupted = StopFlag();
      // Each window start an edge, set the moment its frame is handled.
      if (sync) {
        board.OnWindowStart([&](const protocol::WindowStart& w) {
          std::string why;
          if (sync->OnWindowStart(w, &why) || !sync_error.empty()) return;
          sync_error = why;
          EndProgress();
          std::fprintf(stderr, "mjc trial: %s (the trial goes on)\n", why.c_str());
        });
      }
      // Who it is (one board, its build) and the calibration it runs on, in run.json
      // before anything moves.
      IdentifyOrThrow(board);
      reached = true;
      record.board = board.info();
      std::string why;
      const auto held = host::ReadCalibration(board, &why);
      if (!held) throw Failure(NoAnswer(board), "cannot read its calibration: " + why);
      record.calibration = *held;
      // And the parameters that shape its estimate (all of them: the list is short).
      record.params = host::ReadBoardParams(board, &why);
      if (record.params.is_null()) {
        throw Failure(NoAnswer(board), "cannot read its parameters: " + why);
      }
      host::WriteRunRecord(record, dir);
      // The joint's limits (the description's, sent first), and every amplitude of
      // the plan within the joint's travel the board holds, before anything moves.
      if (robot) {
        const host::ParamWriteOutcome limits = host::SendJointLimits(board, *robot, 500);
        if (limits.end == host::ParamWriteEnd::kNoAnswer) {
          throw end(NoAnswer(board), limits.why + "; nothing moved");
        }
        if (limits.end != host::ParamWriteEnd::kDone) {
          throw end(Exit::kRefused, "sending " + robot->name +
                                        "'s limits: " + limits.why + "; nothing moved");
        }
      }
      const auto travel = host::ReadJointTravel(board, 500, &why);
      if (!travel) throw end(NoAnswer(board), "cannot read its joint's travel: " + why);
      for (const double amplitude : plan) {
        const std::string beyond = host::TravelViolation(amplitude, *travel);
        if (!beyond.empty()) {
          throw end(Exit::kUsage,
                    "node " + std::to_string(node) + ": " + beyond +
                        " (joint_angle_min, joint_angle_max); nothing moved");
        }
      }
      for (std::size_t t = 0; t < plan.size(); ++t) {
        if (pause && t > 0) {
          std::fprintf(stderr, "re-don, then press Enter for trial %zu/%zu\n", t + 1,
                       plan.size());
          std::string line;
          const bool answered = static_cast<bool>(std::getline(std::cin, line));
          if (stopped_by_estop()) {
            throw estop_end(EstopWhat(*estop) + " during the pause before trial " +
                            std::to_string(t + 1) + "; earlier trials are in " + saved);
          }
          if (interrupted || !answered) {
            throw end(Exit::kStopped,
                      std::string(interrupted ? "interrupted"
                                              : "no answer at the prompt (standard "
                                                "input closed)") +
                          " before trial " + std::to_string(t + 1) + " (node " +
                          std::to_string(node) + " at rest); earlier trials are in " +
                          saved);
          }
        }
        protocol::TrialConfig config;
        config.amplitude = Angle::Quantize(host::DegToRad(plan[t]));
        config.frequency_mHz =
            static_cast<std::uint16_t>(std::lround(frequency_hz * 1000));
        config.repetitions = static_cast<std::uint8_t>(reps);
        config.rest_100ms = static_cast<std::uint8_t>(std::lround(rest_s * 10));
        const std::uint64_t broken_before = board.incomplete_windows();
        char label[64];
        std::snprintf(label, sizeof label, "[trial %zu/%zu, %.0f°]", t + 1, plan.size(),
                      plan[t]);
        const auto trial =
            host::RunBoardTrial(board, config, [&](const host::BoardWindow& w) {
              Progress(std::string(label) + " repetition " +
                       std::to_string(w.repetition + 1) + "/" + std::to_string(reps) +
                       (w.motion == Motion::kFlexion ? " flexion" : " extension"));
              // A window that cannot be written (a full disk) does not stop the
              // finger's motion halfway: the trial ends, then the run, with the reason.
              try {
                if (write_error.empty()) {
                  csv->Append(t, plan[t], static_cast<std::uint16_t>(reps), w);
                }
              } catch (const std::exception& e) {
                write_error = e.what();
              }
            });
        EndProgress();
        const std::string unwritten =
            write_error.empty() ? "" : " (" + write_error + ": later windows not saved)";
        if (!trial.completed) {
          // The motor first: a file can wait, a finger should not. Two boards answering
          // for the node may both be moving: both are told. An emergency stop has told
          // every board already.
          const bool stop =
              !stopped_by_estop() && (trial.end == host::TrialEnd::kInterrupted ||
                                      trial.end == host::TrialEnd::kAmbiguous ||
                                      trial.end == host::TrialEnd::kWrongConfig);
          const std::string stopped = stop ? StopMotion(board) : "";
          // What arrived is in windows.csv already, the interrupted trial's windows
          // included.
          const std::string kept =
              std::to_string(csv->rows()) + " windows saved to " + saved + unwritten;
          if (stopped_by_estop()) {
            throw estop_end(ConfirmEmergencyStop(board, *estop) + "; " + kept);
          }
          if (trial.end == host::TrialEnd::kInterrupted) {
            throw end(Exit::kStopped, "interrupted: " + stopped + "; " + kept);
          }
          std::optional<int> fault;
          if (trial.end == host::TrialEnd::kFaulted) {
            fault = static_cast<int>(board.status().fault);
          }
          const Exit exit = ExitOf(trial.end);
          Failure failure =
              end(exit,
                  "trial " + std::to_string(t + 1) + "/" + std::to_string(plan.size()) +
                      " on node " + std::to_string(node) + ": " + trial.error +
                      (stopped.empty() ? "" : " (" + stopped + ")") + "; " + kept,
                  fault);
          // Stopped by another tool ends a run as "stopped", not "interrupted".
          if (trial.end == host::TrialEnd::kStopped) {
            record.end.outcome = "stopped";
            host::WriteRunRecord(record, dir);
          }
          throw failure;
        }
        // A flexion and an extension window a repetition: fewer means some were lost
        // on the bus (the tables then use those that arrived).
        const auto expected = 2 * static_cast<std::size_t>(reps);
        if (trial.windows.size() != expected) {
          std::fprintf(
              stderr,
              "mjc trial: trial %zu: %zu of %zu windows arrived (%llu lost a part "
              "on the bus)\n",
              t + 1, trial.windows.size(), expected,
              static_cast<unsigned long long>(board.incomplete_windows() -
                                              broken_before));
        }
        runs.push_back({plan[t], static_cast<std::uint16_t>(reps), trial.windows});
        if (!write_error.empty()) {
          throw end(Exit::kFailure, "trial " + std::to_string(t + 1) + "/" +
                                        std::to_string(plan.size()) + " ran, but " +
                                        write_error + "; " + std::to_string(csv->rows()) +
                                        " windows saved to " + saved);
        }
      }
    } catch (const Failure& f) {
      // Stopped before the first trial moved (the button pressed at the start, or while
      // the board was asked who it is).
      if (record.end.outcome == "running" && stopped_by_estop()) {
        throw estop_end(EstopWhat(*estop) + "; " + f.what());
      }
      if (record.end.outcome == "running") throw end(f.exit(), f.what());
      throw;
    } catch (const std::exception& e) {
      throw end(Exit::kFailure, e.what());
    }
    estop.reset();  // the motion is over
    record.end.outcome = "completed";
    host::WriteRunRecord(record, dir);
    std::fputs(host::TrialTables(runs, repeatability).c_str(), stdout);
    std::fputs(("\n" + host::AttachmentTable(runs)).c_str(), stdout);
    std::printf("windows: %s\nrun: %s\n", saved.c_str(), (dir / "run.json").c_str());
    if (sync) {
      std::printf("sync: %s: %llu window starts, %llu edges\n", sync_line->name().c_str(),
                  static_cast<unsigned long long>(sync->windows()),
                  static_cast<unsigned long long>(sync->edges()));
      if (!sync_error.empty()) {
        throw Failure("sync line: " + sync_error +
                      " (the trials ran; their windows are saved)");
      }
    }
    std::string why;
    if (!figure) return;
    if (!host::PlotTrials(dir, repeatability, host::RunTitle(record), &why)) {
      throw Failure("no figure: " + why + " (the tables and windows.csv are saved)");
    }
    std::printf("figure: %s\n", (dir / "eta.png").c_str());
  });
}

}  // namespace mjc::cli
