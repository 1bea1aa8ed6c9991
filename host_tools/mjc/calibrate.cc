// mjc calibrate: the paper's calibration on a board over the bus — start the
// increasing-amplitude sweep on the robot alone, record the board's own θ_m and θ_j
// (its angle telemetry), fit c_r, c_l and the joint lag with NLopt, save the record in
// a JSON file and upload it over ISO-TP. Without --robot the fit takes α = 1 and the
// upload replaces only the backlash: the SEA stiffness and joint zero count are the ones
// the board already holds. With --robot FILE (a robot description,
// mjc/host/robot_description.h) the fit takes the joint's α = r_m/r_j (or fits it within
// ±20 % of it with --fit-alpha) and the record carries the joint's K = 2kr_j² and joint
// zero. Its outputs go to a new folder (calibration.json, sweep.csv, run.json), never
// over an earlier run's.

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <optional>
#include <span>
#include <vector>

#include "commands.h"
#include "mjc/build_id.h"
#include "mjc/host/board_client.h"
#include "mjc/host/calibration_fit.h"
#include "mjc/host/calibration_io.h"
#include "mjc/host/describe.h"
#include "mjc/host/joint_limits.h"
#include "mjc/host/report.h"
#include "mjc/host/robot_description.h"
#include "mjc/host/run_record.h"
#include "mjc/host/units.h"

namespace mjc::cli {
namespace {

using protocol::BoardState;
using protocol::CalibrationRecord;
using protocol::CalibrationResult;
using protocol::CommandCode;
using protocol::CommandOutcomeCode;
using protocol::ParamId;

// The files a calibration run writes into its folder (replaced under --force).
const std::vector<std::string> kOutputs = {"calibration.json", "sweep.csv", "run.json",
                                           "run.mat"};

// sweep.csv as the samples arrive: its header at the sweep's start, then each pass's
// samples appended at once (host::AppendFile), so a host that dies mid-sweep leaves
// every sample it had taken.
class SweepCsv {
 public:
  SweepCsv(const std::filesystem::path& path, int rate_hz) : file_(path) {
    file_.Append("# mjc calibrate sweep: the board's angle telemetry at " +
                 std::to_string(rate_hz) + " Hz\nmotor_rad,joint_rad\n");
  }
  void Append(std::span<const host::AngleSample> samples) {
    if (samples.empty()) return;
    std::string text;
    char line[64];
    for (const host::AngleSample& a : samples) {
      std::snprintf(line, sizeof line, "%.9g,%.9g\n", a.motor_rad, a.joint_rad);
      text += line;
    }
    file_.Append(text);
    rows_ += samples.size();
  }
  std::size_t rows() const { return rows_; }

 private:
  host::AppendFile file_;
  std::size_t rows_ = 0;
};

bool SameCalibration(const CalibrationRecord& a, const CalibrationRecord& b) {
  return a.backlash == b.backlash && a.sea_stiffness == b.sea_stiffness &&
         a.joint_zero_count == b.joint_zero_count;
}

}  // namespace

void AddCalibrate(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "calibrate",
      "Sweep, fit the backlash, save and upload the calibration of one board");
  static std::string iface;
  static OutputOptions output;
  static int node = 1, cycles = 10;
  static double amplitude_deg = 30, frequency_hz = 0.5;
  static bool upload = true;
  static std::string robot_path;
  static bool fit_alpha = false;
  static EstopOptions estop_options;
  AddIfaceOption(cmd, &iface);
  AddNodeOption(cmd, &node);
  cmd->add_option("--amplitude-deg", amplitude_deg, "Final sweep amplitude")
      ->check(InRange(1.0, 90.0, "°"))
      ->capture_default_str();
  AddFrequencyOption(cmd, &frequency_hz, "Sweep frequency");
  cmd->add_option("--cycles", cycles, "Sweep cycles")
      ->check(InRange(2, 255))
      ->capture_default_str();
  AddOutputOptions(cmd, &output, "out/calibration");
  AddEstopOptions(cmd, &estop_options, EstopDefault::kConfig);
  cmd->add_flag("!--no-upload", upload, "Fit and save only");
  auto* robot_option = cmd->add_option(
      "--robot", robot_path,
      "Robot description of the joint (robots/*.json): the fit takes its α = r_m/r_j, "
      "the record its SEA stiffness K = 2kr_j², cable friction and joint zero (with "
      "--joint: the joint's, from the hand file; another file is refused)");
  JointSuppliesRobot(cmd, robot_option, &robot_path);
  // Checked in the callback, not with CLI11's needs(): --joint supplies --robot too.
  cmd->add_flag("--fit-alpha", fit_alpha,
                "Fit α too, within ±20 % of the description's (a fit on a bound is "
                "refused; needs --robot or --joint)");
  cmd->callback([] {
    if (fit_alpha && robot_path.empty()) {
      throw Failure(Exit::kUsage,
                    "--fit-alpha needs the joint's description: give "
                    "--robot FILE or --joint NAME");
    }
    // The joint's description first: a bad file moves nothing and writes nothing.
    std::optional<host::RobotDescription> robot;
    nlohmann::json robot_record;  // its content for run.json, as read
    if (!robot_path.empty()) {
      std::string why;
      robot = host::LoadRobotDescription(robot_path, &why);
      if (!robot) throw Failure("robot description refused: " + why);
      robot_record =
          host::RobotRecord(robot_path, host::ReadFileText(robot_path).value_or(""));
      // The sweep turns the motor pulley ±amplitude: the joint follows at α times that.
      const double joint_deg = robot->Alpha() * amplitude_deg;
      if (joint_deg > robot->flexion_limit_deg ||
          -joint_deg < robot->extension_limit_deg) {
        char text[200];
        std::snprintf(text, sizeof text,
                      "--amplitude-deg %.1f moves %s's joint ±%.1f° (α %.3f), beyond its "
                      "travel [%.1f°, %.1f°]",
                      amplitude_deg, robot->name.c_str(), joint_deg, robot->Alpha(),
                      robot->extension_limit_deg, robot->flexion_limit_deg);
        throw Failure(Exit::kUsage, text);
      }
      std::printf("robot %s\n", host::DescribeRobot(*robot, robot_path).c_str());
    }
    std::error_code no_folder;
    const bool created =
        output.out.empty() || !std::filesystem::exists(output.out, no_folder);
    const std::filesystem::path dir =
        PrepareOutputs("mjc calibrate", output, "out/calibration", kOutputs);
    // Whether a board answered: a run that never reached one (no interface, a silent
    // node) leaves no folder behind; once one answered, its run.json says what it said.
    bool reached = false;
    const std::string out_path = (dir / "calibration.json").string();
    host::RunRecord run;
    run.command = "calibrate";
    run.node = node;
    run.iface = iface;
    run.protocol = "calibration sweep";
    run.amplitudes_deg = {amplitude_deg};
    run.frequency_hz = frequency_hz;
    run.repetitions = cycles;
    run.rest_s = 0.5;
    run.started_utc = host::UtcNow();
    run.host = host::HostName();
    run.mjc = build::kDescribe;
    run.pid = static_cast<long>(::getpid());
    if (robot) run.robot = robot_record;
    host::WriteRunRecord(run, dir);  // also finds an unwritable folder now
    // Every way out says how the run ended in run.json, then the Failure.
    std::optional<int> fault;
    // The emergency-stop watch, from before anything moves to the end of the sweep.
    std::unique_ptr<host::EmergencyStopThread> estop;
    const auto stopped_by_estop = [&] { return estop && estop->triggered(); };
    bool estop_said = false;  // the Failure thrown already tells of the emergency stop
    try {
      auto link = OpenLink(iface);
      // Heartbeats flow while the sweep runs: if this tool dies, the board stops it.
      host::BoardClient board(link.get(), static_cast<std::uint8_t>(node),
                              host::HostHeartbeats::kSend);
      // Ctrl-C (or SIGTERM, SIGHUP) ends the sweep: the board is stopped and the samples
      // that arrived are saved. So does the emergency stop.
      estop = GuardMotion(board, "mjc calibrate", iface, estop_options);
      const std::string who = "node " + std::to_string(node);
      std::string why;
      // Who it is (one board, its build), in run.json before anything moves.
      IdentifyOrThrow(board);
      reached = true;
      run.board = board.info();

      // What the board holds now: the new record keeps its stiffness and joint zero.
      const auto held = host::ReadCalibration(board, &why);
      if (!held) {
        throw Failure(
            NoAnswer(board),
            "cannot read " + who + "'s calibration in force, not sweeping: " + why);
      }
      run.calibration = *held;
      // And the parameters that shape its estimate and the sweep's telemetry.
      run.params = host::ReadBoardParams(board, &why);
      if (run.params.is_null()) {
        throw Failure(NoAnswer(board), "cannot read " + who + "'s parameters: " + why);
      }
      host::WriteRunRecord(run, dir);
      // The joint's own torque and travel limits, before anything moves: the board's
      // supervisor stops the sweep at them, and its torque_max stays within the
      // joint's rating; a board holding tighter ones (since its reset) refuses these.
      if (robot) {
        const host::ParamWriteOutcome limits = host::SendJointLimits(board, *robot, 500);
        if (limits.end == host::ParamWriteEnd::kNoAnswer) {
          throw Failure(NoAnswer(board), limits.why + "; nothing moved");
        }
        if (limits.end != host::ParamWriteEnd::kDone) {
          throw Failure(Exit::kRefused, "sending " + robot->name + "'s limits: " +
                                            limits.why + "; nothing moved");
        }
      }
      // The board sends an angle sample every tick_hz / rate ticks: exactly this rate
      // when it divides the tick rate, as the default 1 kHz does.
      const auto rate_hz = board.ReadParam(ParamId::kTelemetryAnglesHz, 500, &why);
      if (!rate_hz) throw Failure(NoAnswer(board), why);
      if (*rate_hz <= 0) {
        throw Failure(who +
                      "'s angle telemetry is off (TelemetryAnglesHz 0): nothing to fit");
      }

      // Created before the sweep is started, so an unwritable file moves nothing.
      const std::filesystem::path sweep_path = dir / "sweep.csv";
      SweepCsv sweep_csv(sweep_path, static_cast<int>(*rate_hz));
      protocol::SweepConfig sweep;
      sweep.end_amplitude = Angle::Quantize(host::DegToRad(amplitude_deg));
      sweep.frequency_mHz = static_cast<std::uint16_t>(std::lround(frequency_hz * 1000));
      sweep.repetitions = static_cast<std::uint8_t>(cycles);
      sweep.rest_100ms = 5;
      // The sweep and the start naming it; the board's MotionConfig confirms it.
      const auto outcome = board.Start(sweep, host::kStartAnswerMs, &why);
      if (!outcome && board.motion_mismatch()) {
        const std::string mismatch = board.mismatch();
        throw Failure(Exit::kRefused,
                      mismatch + "; " + StopMotion(board) + "; nothing recorded");
      }
      if (!outcome) throw Failure(NoAnswer(board), why);
      if (*outcome != CommandOutcomeCode::kAccepted) {
        throw Failure(Exit::kRefused,
                      "the sweep was refused: " + board.RefusalMessage(*outcome));
      }

      // Record the board's angles until it is idle again.
      std::fprintf(stderr, "mjc calibrate: sweeping %.0f° over %d cycles at %.2f Hz...\n",
                   amplitude_deg, cycles, frequency_hz);
      const std::uint64_t dropped_before = link->stats().rx_dropped;
      // The sweep's length: its patience (host::RecordSweep) and the progress line's.
      const double expected_s = cycles / frequency_hz + 2 * sweep.rest_100ms / 10.0;
      // Progress from the board's own clock: its time into the sweep against the sweep's
      // length, and so the cycle it is in.
      std::optional<std::uint32_t> sweep_start;
      std::uint32_t shown_tick = 0;
      const double rest_s = sweep.rest_100ms / 10.0;
      const auto show_progress = [&] {
        if (board.status().state == BoardState::kCalibrating) {
          const std::uint32_t tick = board.status().tick;
          if (!sweep_start) sweep_start = tick;
          if (tick != shown_tick) {
            shown_tick = tick;
            const double in_s = (tick - *sweep_start) / double{protocol::kBoardTickHz};
            const int cycle = std::clamp(
                static_cast<int>(std::floor((in_s - rest_s) * frequency_hz)) + 1, 1,
                cycles);
            char line[96];
            std::snprintf(line, sizeof line, "[sweep] cycle %d/%d (%.1f s of %.1f s)",
                          cycle, cycles, in_s, expected_s);
            Progress(line, "cycle " + std::to_string(cycle));
          }
        }
      };
      // A pass whose samples cannot be written (a full disk) does not stop the motion
      // halfway; the sweep ends, then the run, with the reason.
      std::string write_error;
      const auto take = [&](std::span<const host::AngleSample> taken) {
        try {
          if (write_error.empty()) sweep_csv.Append(taken);
        } catch (const std::exception& e) {
          write_error = e.what();
        }
        show_progress();
      };
      const host::SweepSamples samples = host::RecordSweep(board, expected_s, take, &why);
      EndProgress();
      const std::vector<double>& motor = samples.motor_rad;
      const std::vector<double>& joint = samples.joint_rad;
      // The stop first (the motor must not wait for a file), then the samples, kept
      // however the sweep ended. Two boards answering for the node may both be moving:
      // both are told.
      const bool wrong = !samples.ended && samples.end == host::WaitEnd::kWrongMotion;
      const std::string stopped =
          !samples.ended && !stopped_by_estop() &&
                  (samples.end == host::WaitEnd::kInterrupted ||
                   samples.end == host::WaitEnd::kAmbiguous || wrong)
              ? StopMotion(board)
              : "";
      board.ReleaseMotion();  // the sweep is over
      // Never a record of a motion that is not the one this session started: no sample
      // is appended before the board names this session's sweep, so the file holds
      // none; it goes.
      if (wrong) {
        std::error_code ignored;
        std::filesystem::remove(sweep_path, ignored);
        throw Failure(Exit::kRefused, why + "; " + stopped + "; nothing recorded");
      }
      const std::string kept =
          "; " + std::to_string(sweep_csv.rows()) + " sweep samples saved to " +
          sweep_path.string() +
          (write_error.empty() ? "" : " (" + write_error + ": later samples not saved)");
      if (stopped_by_estop()) {
        estop_said = true;
        throw Failure(Exit::kStopped,
                      ConfirmEmergencyStop(board, *estop) + kept + " (not fitted)");
      }
      estop.reset();  // the motion is over
      if (!samples.ended) {
        switch (samples.end) {
          case host::WaitEnd::kLinkFailed:
            throw Failure(why + kept);
          case host::WaitEnd::kInterrupted:
            throw Failure(Exit::kStopped,
                          "interrupted: " + stopped + kept + " (not fitted)");
          case host::WaitEnd::kAmbiguous:
            throw Failure(Exit::kAmbiguous, why + " (" + stopped + ")" + kept);
          case host::WaitEnd::kWrongMotion:  // thrown above
            throw Failure(Exit::kRefused, why);
          case host::WaitEnd::kSilent:
            throw Failure(Exit::kNoAnswer, "during the sweep, " + why + kept);
          case host::WaitEnd::kBoardTime:
            throw Failure(Exit::kNoAnswer, who +
                                               "'s sweep did not finish within twice its "
                                               "length (" +
                                               why + ")" + kept);
        }
      }
      if (board.status().state == BoardState::kFault) {
        fault = static_cast<int>(board.status().fault);
        throw Failure(Exit::kFaulted, who + " faulted during the sweep: fault " +
                                          host::DescribeFault(board.status().fault) +
                                          kept);
      }
      if (!write_error.empty()) throw Failure("the sweep ran, but " + write_error + kept);
      // A lost sample shifts every later one in time: the lag fit would read it as lag.
      const std::uint64_t dropped = link->stats().rx_dropped - dropped_before;
      const std::uint64_t malformed = samples.malformed;
      if (dropped + malformed > 0) {
        throw Failure("the record has gaps (" + std::to_string(dropped) +
                      " frames dropped by the kernel, " + std::to_string(malformed) +
                      " malformed): not fitting it; rerun the sweep on a quieter bus");
      }

      const host::SweepCalibration fitted = host::FitSweep(
          motor, joint, *rate_hz, held->record, robot ? &*robot : nullptr, fit_alpha);
      const host::BacklashFit& fit = fitted.fit;
      if (!fitted.record) throw Failure("fit not usable: " + fitted.why);
      CalibrationRecord record = *fitted.record;
      record.fitted_at_unix_s = static_cast<std::uint64_t>(std::time(nullptr));
      std::printf(
          "fit over %zu samples at %d Hz: c_r %.4f°, c_l %.4f°, lag %.2f ms, rms %.4f°, "
          "%.1f ms\n",
          motor.size(), *rate_hz, host::RadToDeg(fit.c_right_rad),
          host::RadToDeg(fit.c_left_rad), fit.lag_s * 1e3,
          host::RadToDeg(fit.rms_error_rad), fit.elapsed_ms);
      std::printf(
          "α %.4f (%s), SEA stiffness %.4f N·m/rad, cable friction %.3f N·m%s and joint "
          "zero %u (%s)\n",
          record.backlash.alpha.ToDouble(),
          !robot      ? "assumed 1, no --robot"
          : fit_alpha ? "fitted within ±20 % of the description's"
                      : "the description's",
          record.sea_stiffness.ToDouble(), record.backlash.cable_friction.ToDouble(),
          record.backlash.cable_friction == Torque{} ? " (not modelled)" : "",
          unsigned{record.joint_zero_count},
          robot ? ("from " + robot->name).c_str() : "kept from the board");
      // Saved before the upload, so a failed upload loses nothing: `mjc cal upload`
      // sends the file later.
      host::WriteFile(out_path, host::CalibrationToJson(record).dump(2) + "\n");
      if (!upload) {
        std::printf("saved %s (not uploaded)\n", out_path.c_str());
        run.end.outcome = "completed";
        run.end.message = "not uploaded (--no-upload)";
        host::WriteRunRecord(run, dir);
        return;
      }

      const auto sent = host::UploadCalibration(iface, node, record, 1000, &why);
      const std::string saved = "; the fit is saved in " + out_path;
      switch (sent.status) {
        case host::UploadStatus::kLinkFailed:
          throw Failure("cannot upload to " + who + ": " + why + saved);
        case host::UploadStatus::kNoAnswer:
          throw Failure(Exit::kNoAnswer,
                        who + " did not answer the upload (" + why + ")" + saved);
        case host::UploadStatus::kMalformedReply:
          throw Failure(Exit::kNoAnswer,
                        "malformed answer to the upload: " + why + saved);
        case host::UploadStatus::kAnswered:
          break;
      }
      if (sent.result != CalibrationResult::kAccepted) {
        throw Failure(Exit::kRefused,
                      who + " refused the calibration: " +
                          host::DescribeCalibrationResult(sent.result, sent.detail) +
                          saved);
      }
      // Read back: the board must hold exactly what was sent.
      const auto back = host::ReadCalibration(board, &why);
      if (!back)
        throw Failure(NoAnswer(board), "cannot read the calibration back: " + why);
      if (!back->calibrated || !SameCalibration(back->record, record)) {
        throw Failure(Exit::kRefused,
                      who + " holds a different calibration than was sent");
      }
      std::printf("node %d calibrated (upload %.1f ms, read back identical); saved %s\n",
                  node, sent.elapsed_ms, out_path.c_str());
    } catch (const Failure& f) {
      EndProgress();
      if (stopped_by_estop()) {
        run.end = {"emergency_stop", std::nullopt,
                   estop_said ? f.what() : EstopWhat(*estop) + "; " + f.what()};
        host::WriteRunRecord(run, dir);
        throw Failure(Exit::kStopped, run.end.message);
      }
      run.end = {OutcomeOf(f.exit()), fault, f.what()};
      host::WriteRunRecord(run, dir);
      if (!reached && f.exit() != Exit::kAmbiguous) {
        host::DiscardUnstartedRun(dir, kOutputs, created);
      }
      throw;
    } catch (const std::exception& e) {
      run.end = {"failed", std::nullopt, e.what()};
      host::WriteRunRecord(run, dir);
      if (!reached) host::DiscardUnstartedRun(dir, kOutputs, created);
      throw;
    }
    run.end.outcome = "completed";
    host::WriteRunRecord(run, dir);
  });
}

}  // namespace mjc::cli
