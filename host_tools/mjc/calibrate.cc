// mjc calibrate: the paper's calibration on a board over the bus — start the
// increasing-amplitude sweep on the robot alone, record the board's own θ_m and θ_j
// (the 1 kHz angle telemetry), fit c_r, c_l and the joint lag with NLopt, save the
// record in a JSON file and upload it over ISO-TP.
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <filesystem>

#include "commands.h"
#include "mjc/host/calibration_fit.h"
#include "mjc/host/calibration_io.h"
#include "mjc/host/can_link.h"
#include "mjc/host/report.h"
#include "mjc/host/units.h"
#include "mjc/protocol/codec.h"

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
    const std::string who = "node " + std::to_string(node);
    std::string why;
    const auto n = static_cast<std::uint8_t>(node);
    const host::IdFilter only_node{n, 0x00F};
    link->SetFilters({&only_node, 1}, &why);

    protocol::SweepConfig sweep;
    sweep.end_amplitude = Angle::Quantize(host::DegToRad(amplitude_deg));
    sweep.frequency_mHz = static_cast<std::uint16_t>(std::lround(frequency_hz * 1000));
    sweep.repetitions = static_cast<std::uint8_t>(cycles);
    sweep.rest_100ms = 5;
    const std::uint8_t sequence = static_cast<std::uint8_t>(std::time(nullptr) & 0xFF);
    if (!link->Send(Encode(sweep, n), &why) ||
        !link->Send(Encode(Command{CommandCode::kStartSweep, sequence}, n), &why)) {
      throw Failure(why);
    }
    // The command's answer.
    bool answered = false;
    const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(1);
    while (!answered && std::chrono::steady_clock::now() < until) {
      const auto r = link->Receive(50, &why);
      if (r.status == host::ReceiveStatus::kError) throw Failure(why);
      protocol::CommandResult result;
      if (r && Decode(r->frame, &result) == DecodeError::kOk &&
          result.sequence == sequence) {
        answered = true;
        if (result.outcome != CommandOutcomeCode::kAccepted) {
          throw Failure(Exit::kRefused,
                        who + " refused the sweep (outcome " +
                            std::to_string(static_cast<int>(result.outcome)) + ")");
        }
      }
    }
    if (!answered)
      throw Failure(Exit::kNoAnswer, who + " on " + iface + " did not answer");
    // Record the board's angles until it is idle again.
    std::vector<double> motor, joint;
    const double expected_s = cycles / frequency_hz + 1.0;
    const auto deadline = std::chrono::steady_clock::now() +
                          std::chrono::duration<double>(expected_s * 3 + 5);
    bool done = false;
    std::fprintf(stderr, "mjc calibrate: sweeping %.0f° over %d cycles at %.2f Hz...\n",
                 amplitude_deg, cycles, frequency_hz);
    while (!done && std::chrono::steady_clock::now() < deadline) {
      const auto r = link->Receive(100, &why);
      if (r.status == host::ReceiveStatus::kError) throw Failure(why);
      if (!r) continue;
      TelemetryAngles a;
      Heartbeat hb;
      if (Decode(r->frame, &a) == DecodeError::kOk) {
        motor.push_back(a.motor.ToDouble());
        joint.push_back(a.joint.ToDouble());
      } else if (Decode(r->frame, &hb) == DecodeError::kOk && motor.size() > 100 &&
                 hb.state != BoardState::kCalibrating) {
        done = true;
        if (hb.state == BoardState::kFault) {
          throw Failure(Exit::kFaulted, who + " faulted during the sweep (fault " +
                                            std::to_string(static_cast<int>(hb.fault)) +
                                            ")");
        }
      }
    }
    if (!done) throw Failure(Exit::kNoAnswer, "the sweep did not finish in time");
    host::BacklashFitOptions options;
    options.fit_lag = true;
    options.sample_rate_hz = 1000;  // the board's angle telemetry rate
    const host::BacklashFit fit = host::FitBacklash(motor, joint, options);
    const auto config = host::ToFirmwareConfig(fit, &why);
    if (!config) throw Failure("fit not usable: " + why);
    CalibrationRecord record;
    record.backlash = *config;
    record.fit_rms_urad = static_cast<std::uint32_t>(fit.rms_error_rad * 1e6);
    record.fit_lag_us = static_cast<std::uint32_t>(fit.lag_s * 1e6);
    record.fitted_at_unix_s = static_cast<std::uint64_t>(std::time(nullptr));
    std::printf(
        "fit over %zu samples: c_r %.4f°, c_l %.4f°, lag %.2f ms, rms %.4f°, %.1f ms\n",
        motor.size(), host::RadToDeg(fit.c_right_rad), host::RadToDeg(fit.c_left_rad),
        fit.lag_s * 1e3, host::RadToDeg(fit.rms_error_rad), fit.elapsed_ms);
    // Saved before the upload, so a failed upload loses nothing: `mjc cal upload`
    // sends the file later.
    host::WriteFile(out_path, host::CalibrationToJson(record).dump(2) + "\n");
    if (!upload) {
      std::printf("saved %s (not uploaded)\n", out_path.c_str());
      return;
    }
    const auto outcome = host::UploadCalibration(iface, node, record, 1000, &why);
    const std::string saved = "; the fit is saved in " + out_path;
    if (!outcome) throw Failure("cannot upload to " + who + ": " + why + saved);
    if (!outcome->answered) {
      throw Failure(Exit::kNoAnswer,
                    who + " did not answer the upload (" + why + ")" + saved);
    }
    if (outcome->result != CalibrationResult::kAccepted) {
      throw Failure(
          Exit::kRefused,
          who + " refused the calibration: " +
              host::DescribeCalibrationResult(outcome->result, outcome->detail) + saved);
    }
    // Read back: the board must hold exactly what was sent.
    const auto back = host::DownloadCalibration(iface, node, &why);
    if (!back) throw Failure(Exit::kNoAnswer, "cannot read the calibration back: " + why);
    const bool same = back->backlash.c_right == record.backlash.c_right &&
                      back->backlash.c_left == record.backlash.c_left &&
                      back->backlash.alpha == record.backlash.alpha &&
                      back->sea_stiffness == record.sea_stiffness &&
                      back->joint_zero_count == record.joint_zero_count;
    if (!same) {
      throw Failure(Exit::kRefused, who + " holds a different calibration than was sent");
    }
    std::printf("node %d calibrated (upload %.1f ms, read back identical); saved %s\n",
                node, outcome->elapsed_ms, out_path.c_str());
  });
}

}  // namespace mjc::cli
