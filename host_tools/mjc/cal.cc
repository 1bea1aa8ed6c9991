// mjc cal show|upload|download: a calibration file, its upload to a board over ISO-TP,
// and the calibration a board holds.
#include <cstdio>
#include <fstream>

#include "commands.h"
#include "mjc/host/calibration_io.h"
#include "mjc/host/describe.h"
#include "mjc/host/report.h"

namespace mjc::cli {
namespace {

// The calibration in `file`, checked with the board's rules; throws Failure naming the
// file and the field.
protocol::CalibrationRecord Load(const std::string& file) {
  std::ifstream in(file);
  if (!in) throw Failure("cannot read " + file);
  nlohmann::json j;
  try {
    in >> j;
  } catch (const std::exception& e) {
    throw Failure(file + " is not JSON: " + e.what());
  }
  std::string why;
  const auto record = host::CalibrationFromJson(j, &why);
  if (!record) throw Failure(file + ": " + why);
  return *record;
}

}  // namespace

void AddCal(CLI::App& app) {
  auto* cal = app.add_subcommand("cal", "Show, upload or download a calibration");
  cal->require_subcommand(1);
  static std::string file, iface, out;
  static int node = 1, timeout_ms = 1000;

  auto* show =
      cal->add_subcommand("show", "Print a calibration file after the board's checks");
  show->add_option("file", file, "Calibration JSON (as mjc calibrate writes)")
      ->required();
  show->callback(
      [] { std::printf("%s\n", host::CalibrationToJson(Load(file)).dump(2).c_str()); });

  auto* download = cal->add_subcommand("download", "Read a board's calibration back");
  AddIfaceOption(download, &iface);
  AddNodeOption(download, &node);
  download->add_option("--out", out, "Write it to this file (default: print)");
  download->callback([] {
    auto link = OpenLink(iface);
    host::BoardClient board(link.get(), static_cast<std::uint8_t>(node));
    std::string why;
    const auto held = host::ReadCalibration(board, &why);
    if (!held) throw Failure(NoAnswer(board), why);
    if (!held->calibrated) {
      throw Failure(Exit::kRefused,
                    "node " + std::to_string(node) + " is not calibrated");
    }
    // The fit's RMS, lag and time are not readable over the bus: leave them out rather
    // than print zeros as if they were measured.
    nlohmann::json j = host::CalibrationToJson(held->record);
    for (const char* key : {"fit_rms_urad", "fit_lag_us", "fitted_at_unix_s"})
      j.erase(key);
    const std::string text = j.dump(2) + "\n";
    if (out.empty()) {
      std::fputs(text.c_str(), stdout);
    } else {
      host::WriteFile(out, text);
    }
  });

  auto* upload =
      cal->add_subcommand("upload", "Upload a calibration file to a board (ISO-TP)");
  upload->add_option("file", file, "Calibration JSON")->required();
  AddIfaceOption(upload, &iface);
  AddNodeOption(upload, &node);
  upload->add_option("--timeout-ms", timeout_ms, "Wait this long for the board's answer")
      ->check(CLI::Range(10, 60000))
      ->capture_default_str();
  upload->callback([] {
    const protocol::CalibrationRecord record = Load(file);
    std::string why;
    const auto outcome = host::UploadCalibration(iface, node, record, timeout_ms, &why);
    const std::string who = "node " + std::to_string(node) + " on " + iface;
    switch (outcome.status) {
      case host::UploadStatus::kLinkFailed:
        throw Failure("cannot send to " + who + ": " + why);
      case host::UploadStatus::kNoAnswer:
        throw Failure(Exit::kNoAnswer, who + " did not answer (" + why + ")");
      case host::UploadStatus::kMalformedReply:
        throw Failure(Exit::kNoAnswer, "malformed answer: " + why);
      case host::UploadStatus::kAnswered:
        break;
    }
    if (outcome.result != protocol::CalibrationResult::kAccepted) {
      throw Failure(Exit::kRefused,
                    who + " refused it: " +
                        host::DescribeCalibrationResult(outcome.result, outcome.detail));
    }
    std::printf("node %d accepted the calibration (%.1f ms)\n", node, outcome.elapsed_ms);
  });
}

}  // namespace mjc::cli
