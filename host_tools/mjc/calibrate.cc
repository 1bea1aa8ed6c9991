// mjc calibrate: the paper's calibration on a board over the bus — start the
// increasing-amplitude sweep on the robot alone, record the board's own θ_m and θ_j
// (the 1 kHz angle telemetry), fit c_r, c_l and the joint lag with NLopt, upload the
// record over ISO-TP, and keep a copy in a JSON file.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <fstream>

#include "commands.h"
#include "mjc/host/calibration_fit.h"
#include "mjc/host/calibration_io.h"
#include "mjc/host/can_link.h"
#include "mjc/protocol/codec.h"

namespace mjc::cli {
namespace {

using namespace mjc::protocol;
constexpr double kDeg = 3.14159265358979323846 / 180.0;

}  // namespace

void AddCalibrate(CLI::App& app, int* status) {
  auto* cmd = app.add_subcommand(
      "calibrate",
      "Sweep, fit the backlash, upload and save the calibration of one board");
  static std::string iface = "vcan0", out_path = "calibration.json";
  static int node = 1, cycles = 10;
  static double amplitude_deg = 30, frequency_hz = 0.5;
  static bool upload = true;
  cmd->add_option("--iface", iface, "CAN interface")->capture_default_str();
  cmd->add_option("--node", node, "Node id")
      ->check(CLI::Range(1, 8))
      ->capture_default_str();
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
  cmd->callback([status] {
    std::string why;
    auto link = host::SocketCanLink::Open(iface, &why);
    if (!link) {
      std::fprintf(stderr, "mjc calibrate: %s\n", why.c_str());
      *status = 1;
      return;
    }
    const auto n = static_cast<std::uint8_t>(node);
    const host::IdFilter only_node{n, 0x00F};
    link->SetFilters({&only_node, 1}, &why);

    protocol::SweepConfig sweep;
    sweep.end_amplitude = Angle::Quantize(amplitude_deg * kDeg);
    sweep.frequency_mHz = static_cast<std::uint16_t>(std::lround(frequency_hz * 1000));
    sweep.repetitions = static_cast<std::uint8_t>(cycles);
    sweep.rest_100ms = 5;
    link->Send(Encode(sweep, n), &why);
    const std::uint8_t sequence = static_cast<std::uint8_t>(std::time(nullptr) & 0xFF);
    if (!link->Send(Encode(Command{CommandCode::kStartSweep, sequence}, n), &why)) {
      std::fprintf(stderr, "mjc calibrate: %s\n", why.c_str());
      *status = 1;
      return;
    }
    // The command's answer.
    bool answered = false;
    const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(1);
    while (!answered && std::chrono::steady_clock::now() < until) {
      const auto r = link->Receive(50, &why);
      if (r.status == host::ReceiveStatus::kError) {
        std::fprintf(stderr, "mjc calibrate: %s\n", why.c_str());
        *status = 1;
        return;
      }
      protocol::CommandResult result;
      if (r && Decode(r->frame, &result) == DecodeError::kOk &&
          result.sequence == sequence) {
        answered = true;
        if (result.outcome != CommandOutcomeCode::kAccepted) {
          std::fprintf(stderr, "mjc calibrate: node %d refused the sweep (outcome %d)\n",
                       node, static_cast<int>(result.outcome));
          *status = 4;
          return;
        }
      }
    }
    if (!answered) {
      std::fprintf(stderr, "mjc calibrate: node %d on %s did not answer\n", node,
                   iface.c_str());
      *status = 3;
      return;
    }
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
      if (r.status == host::ReceiveStatus::kError) {
        std::fprintf(stderr, "mjc calibrate: %s\n", why.c_str());
        *status = 1;
        return;
      }
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
          std::fprintf(stderr,
                       "mjc calibrate: node %d faulted during the sweep (fault %d)\n",
                       node, static_cast<int>(hb.fault));
          *status = 5;
          return;
        }
      }
    }
    if (!done) {
      std::fprintf(stderr, "mjc calibrate: the sweep did not finish in time\n");
      *status = 3;
      return;
    }
    host::BacklashFitOptions options;
    options.fit_lag = true;
    options.sample_rate_hz = 1000;  // the board's angle telemetry rate
    const host::BacklashFit fit = host::FitBacklash(motor, joint, options);
    const auto config = host::ToFirmwareConfig(fit, &why);
    if (!config) {
      std::fprintf(stderr, "mjc calibrate: fit not usable: %s\n", why.c_str());
      *status = 4;
      return;
    }
    CalibrationRecord record;
    record.backlash = *config;
    record.fit_rms_urad = static_cast<std::uint32_t>(fit.rms_error_rad * 1e6);
    record.fit_lag_us = static_cast<std::uint32_t>(fit.lag_s * 1e6);
    record.fitted_at_unix_s = static_cast<std::uint64_t>(std::time(nullptr));
    std::printf(
        "fit over %zu samples: c_r %.4f°, c_l %.4f°, lag %.2f ms, rms %.4f°, %.1f ms\n",
        motor.size(), fit.c_right_rad / kDeg, fit.c_left_rad / kDeg, fit.lag_s * 1e3,
        fit.rms_error_rad / kDeg, fit.elapsed_ms);
    const auto persist = [&record] {
      std::ofstream(out_path) << host::CalibrationToJson(record).dump(2) << '\n';
    };
    if (!upload) {
      persist();
      std::printf("saved %s (not uploaded)\n", out_path.c_str());
      *status = 0;
      return;
    }
    const auto outcome = host::UploadCalibration(iface, node, record, 1000, &why);
    if (!outcome || !outcome->answered) {
      std::fprintf(stderr, "mjc calibrate: upload to node %d failed: %s\n", node,
                   why.c_str());
      *status = 3;
    } else if (outcome->result != CalibrationResult::kAccepted) {
      std::fprintf(
          stderr, "mjc calibrate: node %d refused the calibration: %s\n", node,
          host::DescribeCalibrationResult(outcome->result, outcome->detail).c_str());
      *status = 4;
    } else {
      // Read back: the board must hold exactly what was sent.
      const auto back = host::DownloadCalibration(iface, node, &why);
      const bool same = back && back->backlash.c_right == record.backlash.c_right &&
                        back->backlash.c_left == record.backlash.c_left &&
                        back->backlash.alpha == record.backlash.alpha &&
                        back->sea_stiffness == record.sea_stiffness &&
                        back->joint_zero_count == record.joint_zero_count;
      if (!same) {
        std::fprintf(stderr, "mjc calibrate: node %d read back %s\n", node,
                     back ? "a different calibration" : why.c_str());
        *status = 6;
        return;
      }
      persist();
      std::printf("node %d calibrated (upload %.1f ms, read back identical); saved %s\n",
                  node, outcome->elapsed_ms, out_path.c_str());
      *status = 0;
    }
  });
}

}  // namespace mjc::cli
