// mjc calibrate: the paper's calibration on a board over the bus — start the
// increasing-amplitude sweep on the robot alone, record the board's own θ_m and θ_j
// (its angle telemetry), fit c_r, c_l and the joint lag with NLopt, save the record in
// a JSON file and upload it over ISO-TP. The upload replaces only the backlash: the SEA
// stiffness and joint zero count are the ones the board already holds.
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <vector>

#include "commands.h"
#include "mjc/host/board_client.h"
#include "mjc/host/calibration_fit.h"
#include "mjc/host/calibration_io.h"
#include "mjc/host/describe.h"
#include "mjc/host/report.h"
#include "mjc/host/units.h"

namespace mjc::cli {
namespace {

using namespace mjc::protocol;

// Fails now, not after a minute of sweeping, when `path` cannot be written.
void CheckWritable(const std::filesystem::path& path) {
  const std::filesystem::path probe =
      std::filesystem::exists(path)
          ? path
          : (path.has_parent_path() ? path.parent_path() : std::filesystem::path("."));
  if (::access(probe.c_str(), W_OK) != 0) {
    throw Failure("cannot write " + path.string() + ": " + std::strerror(errno));
  }
}

// The sweep's samples beside the calibration file: calibration.json →
// calibration.sweep.csv. Kept whether the sweep ended or was interrupted, so what the
// board recorded is never lost and can be fitted again.
std::filesystem::path SweepPath(const std::filesystem::path& out) {
  std::filesystem::path p = out;
  return p.replace_extension(".sweep.csv");
}

void WriteSweep(const std::filesystem::path& path, int rate_hz,
                const std::vector<double>& motor, const std::vector<double>& joint) {
  std::string text = "# mjc calibrate sweep: the board's angle telemetry at " +
                     std::to_string(rate_hz) + " Hz\nmotor_rad,joint_rad\n";
  char line[64];
  for (std::size_t i = 0; i < motor.size(); ++i) {
    std::snprintf(line, sizeof line, "%.9g,%.9g\n", motor[i], joint[i]);
    text += line;
  }
  host::WriteFile(path, text);
}

bool SameCalibration(const CalibrationRecord& a, const CalibrationRecord& b) {
  return a.backlash.c_right == b.backlash.c_right &&
         a.backlash.c_left == b.backlash.c_left && a.backlash.alpha == b.backlash.alpha &&
         a.sea_stiffness == b.sea_stiffness && a.joint_zero_count == b.joint_zero_count;
}

}  // namespace

void AddCalibrate(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "calibrate",
      "Sweep, fit the backlash, save and upload the calibration of one board");
  static std::string iface, out_path = "calibration.json";
  static int node = 1, cycles = 10;
  static double amplitude_deg = 30, frequency_hz = 0.5;
  static bool upload = true;
  AddIfaceOption(cmd, &iface);
  AddNodeOption(cmd, &node);
  cmd->add_option("--amplitude-deg", amplitude_deg, "Final sweep amplitude")
      ->check(CLI::Range(1.0, 90.0))
      ->capture_default_str();
  cmd->add_option("--frequency-hz", frequency_hz, "Sweep frequency")
      ->check(CLI::Range(kMinFrequencyHz, kMaxFrequencyHz))
      ->capture_default_str();
  cmd->add_option("--cycles", cycles, "Sweep cycles")
      ->check(CLI::Range(2, 255))
      ->capture_default_str();
  cmd->add_option("--out", out_path, "Where to save the calibration")
      ->capture_default_str();
  cmd->add_flag("!--no-upload", upload, "Fit and save only");
  cmd->callback([] {
    CheckWritable(out_path);
    auto link = OpenLink(iface);
    // Heartbeats flow while the sweep runs: if this tool dies, the board stops it.
    host::BoardClient board(link.get(), static_cast<std::uint8_t>(node),
                            host::HostHeartbeats::kSend);
    SayBusOff(board, "mjc calibrate", iface);
    // Ctrl-C (or SIGTERM, SIGHUP) ends the sweep: the board is stopped and the samples
    // that arrived are saved.
    const std::atomic<bool>& interrupted = StopOnSignals();
    board.SetInterrupt(&interrupted);
    const std::string who = "node " + std::to_string(node);
    std::string why;

    // What the board holds now: the new record keeps its stiffness and joint zero.
    const auto held = host::ReadCalibration(board, &why);
    if (!held) {
      throw Failure(NoAnswer(board), "cannot read " + who +
                                         "'s calibration in force, not sweeping: " + why);
    }
    // The board sends an angle sample every tick_hz / rate ticks: exactly this rate
    // when it divides the tick rate, as the default 1 kHz does.
    const auto rate_hz = board.ReadParam(ParamId::kTelemetryAnglesHz, 500, &why);
    if (!rate_hz) throw Failure(NoAnswer(board), why);
    if (*rate_hz <= 0) {
      throw Failure(who +
                    "'s angle telemetry is off (TelemetryAnglesHz 0): nothing to fit");
    }

    protocol::SweepConfig sweep;
    sweep.end_amplitude = Angle::Quantize(host::DegToRad(amplitude_deg));
    sweep.frequency_mHz = static_cast<std::uint16_t>(std::lround(frequency_hz * 1000));
    sweep.repetitions = static_cast<std::uint8_t>(cycles);
    sweep.rest_100ms = 5;
    if (!board.Send(sweep, &why)) throw Failure(why);
    const auto outcome =
        board.Command(CommandCode::kStartSweep, host::kStartAnswerMs, &why);
    if (!outcome) throw Failure(NoAnswer(board), why);
    if (*outcome != CommandOutcomeCode::kAccepted) {
      throw Failure(Exit::kRefused, who + " refused the sweep: " +
                                        std::string(host::OutcomeName(*outcome)));
    }

    // Record the board's angles until it is idle again.
    std::fprintf(stderr, "mjc calibrate: sweeping %.0f° over %d cycles at %.2f Hz...\n",
                 amplitude_deg, cycles, frequency_hz);
    const std::uint64_t dropped_before = link->stats().rx_dropped;
    const std::uint64_t malformed_before = board.malformed();
    board.TakeAngles();
    board.KeepAngles(true);
    // Followed at the board's pace (host::Patience): at most twice the sweep's own
    // length in the board's time, and the board may not fall silent.
    const double expected_s = cycles / frequency_hz + 2 * sweep.rest_100ms / 10.0;
    std::vector<double> motor, joint;
    bool sweeping_seen = false;
    const auto finished = [&] {
      for (const host::AngleSample& a : board.TakeAngles()) {
        motor.push_back(a.motor_rad);
        joint.push_back(a.joint_rad);
      }
      const BoardState state = board.status().state;
      if (state == BoardState::kCalibrating) sweeping_seen = true;
      return state == BoardState::kFault || (sweeping_seen && state == BoardState::kIdle);
    };
    const host::Patience patience{
        std::chrono::milliseconds(static_cast<long>(2000 * expected_s) + 2000)};
    host::WaitEnd end{};
    const bool ended = board.Await(finished, patience, &end, &why);
    board.KeepAngles(false);
    // The stop first (the motor must not wait for a file), then the samples, kept
    // however the sweep ended.
    const std::string stopped =
        !ended && end == host::WaitEnd::kInterrupted ? StopMotion(board) : "";
    const std::filesystem::path sweep_path = SweepPath(out_path);
    WriteSweep(sweep_path, *rate_hz, motor, joint);
    const std::string kept = "; " + std::to_string(motor.size()) +
                             " sweep samples saved to " + sweep_path.string();
    if (!ended) {
      switch (end) {
        case host::WaitEnd::kLinkFailed:
          throw Failure(why + kept);
        case host::WaitEnd::kInterrupted:
          throw Failure(Exit::kStopped,
                        "interrupted: " + stopped + kept + " (not fitted)");
        case host::WaitEnd::kSilent:
          throw Failure(Exit::kNoAnswer,
                        who + " went silent during the sweep (" + why + ")" + kept);
        case host::WaitEnd::kBoardTime:
          throw Failure(Exit::kNoAnswer, who +
                                             "'s sweep did not finish within twice its "
                                             "length (" +
                                             why + ")" + kept);
      }
    }
    if (board.status().state == BoardState::kFault) {
      throw Failure(Exit::kFaulted, who + " faulted during the sweep: fault " +
                                        host::DescribeFault(board.status().fault) + kept);
    }
    // A lost sample shifts every later one in time: the lag fit would read it as lag.
    const std::uint64_t dropped = link->stats().rx_dropped - dropped_before;
    const std::uint64_t malformed = board.malformed() - malformed_before;
    if (dropped + malformed > 0) {
      throw Failure("the record has gaps (" + std::to_string(dropped) +
                    " frames dropped by the kernel, " + std::to_string(malformed) +
                    " malformed): not fitting it; rerun the sweep on a quieter bus");
    }

    host::BacklashFitOptions options;
    options.fit_lag = true;
    options.sample_rate_hz = *rate_hz;
    const host::BacklashFit fit = host::FitBacklash(motor, joint, options);
    const auto config = host::ToFirmwareConfig(fit, &why);
    if (!config) throw Failure("fit not usable: " + why);
    CalibrationRecord record = held->record;
    record.backlash = *config;
    record.fit_rms_urad =
        static_cast<std::uint32_t>(std::lround(fit.rms_error_rad * 1e6));
    record.fit_lag_us = static_cast<std::uint32_t>(std::lround(fit.lag_s * 1e6));
    record.fitted_at_unix_s = static_cast<std::uint64_t>(std::time(nullptr));
    std::printf(
        "fit over %zu samples at %d Hz: c_r %.4f°, c_l %.4f°, lag %.2f ms, rms %.4f°, "
        "%.1f ms\n",
        motor.size(), *rate_hz, host::RadToDeg(fit.c_right_rad),
        host::RadToDeg(fit.c_left_rad), fit.lag_s * 1e3,
        host::RadToDeg(fit.rms_error_rad), fit.elapsed_ms);
    // Saved before the upload, so a failed upload loses nothing: `mjc cal upload`
    // sends the file later.
    host::WriteFile(out_path, host::CalibrationToJson(record).dump(2) + "\n");
    if (!upload) {
      std::printf("saved %s (not uploaded)\n", out_path.c_str());
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
        throw Failure(Exit::kNoAnswer, "malformed answer to the upload: " + why + saved);
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
    if (!back) throw Failure(NoAnswer(board), "cannot read the calibration back: " + why);
    if (!back->calibrated || !SameCalibration(back->record, record)) {
      throw Failure(Exit::kRefused, who + " holds a different calibration than was sent");
    }
    std::printf("node %d calibrated (upload %.1f ms, read back identical); saved %s\n",
                node, sent.elapsed_ms, out_path.c_str());
  });
}

}  // namespace mjc::cli
