// mjc cal show|upload|download: a calibration file, its upload to a board over ISO-TP,
// and the calibration a board holds.
#include <cstdio>
#include <ctime>
#include <fstream>

#include "commands.h"
#include "mjc/host/calibration_io.h"
#include "mjc/host/describe.h"
#include "mjc/host/report.h"
#include "mjc/host/units.h"

namespace mjc::cli {
namespace {

// The calibration in `file`, checked with the board's rules; throws Failure naming the
// file and the field. Values the board accepts but no Maestro joint has are said on
// stderr, a line each, under `command`'s name.
protocol::CalibrationRecord Load(const std::string& file, const char* command) {
  const nlohmann::json j = ReadJsonObjectFile(file);
  std::string why;
  std::vector<std::string> warnings;
  const auto record = host::CalibrationFromJson(j, &why, &warnings);
  if (!record) throw Failure(file + ": " + why);
  for (const std::string& w : warnings) {
    std::fprintf(stderr, "%s: warning: %s: %s\n", command, file.c_str(), w.c_str());
  }
  return *record;
}

// For people: the values in their units, the fit when the file has one.
std::string Describe(const protocol::CalibrationRecord& r) {
  char text[512];
  std::snprintf(text, sizeof text,
                "backlash   c_right %+.4f°  c_left %+.4f°  alpha %.4f\n"
                "cable      friction %.3f N·m%s\n"
                "SEA        stiffness %.4f N·m/rad\n"
                "joint      zero count %u\n",
                host::RadToDeg(r.backlash.c_right.ToDouble()),
                host::RadToDeg(r.backlash.c_left.ToDouble()), r.backlash.alpha.ToDouble(),
                r.backlash.cable_friction.ToDouble(),
                r.backlash.cable_friction == Torque{} ? " (not modelled)" : "",
                r.sea_stiffness.ToDouble(), static_cast<unsigned>(r.joint_zero_count));
  std::string out = text;
  if (r.fitted_at_unix_s != 0) {
    const auto when = static_cast<std::time_t>(r.fitted_at_unix_s);
    char date[32];
    std::strftime(date, sizeof date, "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&when));
    std::snprintf(text, sizeof text, "fit        rms %.4f°  lag %.2f ms  at %s\n",
                  host::RadToDeg(r.fit_rms_urad * 1e-6), r.fit_lag_us * 1e-3, date);
    out += text;
  } else {
    out += "fit        none recorded (read from a board, or written by hand)\n";
  }
  return out;
}

}  // namespace

void AddCal(CLI::App& app) {
  auto* cal = app.add_subcommand("cal", "Show, upload or download a calibration");
  cal->require_subcommand(1);
  static std::string file, iface, out;
  static int node = 1, timeout_ms = 1000;
  static bool json = false, force = false;

  auto* show =
      cal->add_subcommand("show", "Print a calibration file after the board's checks");
  show->add_option("file", file, "Calibration JSON (as mjc calibrate writes)")
      ->required();
  show->add_flag("--json", json, "Print it as JSON (the file's own form, checked)");
  show->callback([] {
    const protocol::CalibrationRecord record = Load(file, "mjc cal show");
    if (json) {
      std::printf("%s\n", host::CalibrationToJson(record).dump(2).c_str());
    } else {
      std::printf("%s (accepted by the board's checks)\n%s", file.c_str(),
                  Describe(record).c_str());
    }
  });

  auto* download = cal->add_subcommand("download", "Read a board's calibration back");
  AddIfaceOption(download, &iface);
  AddNodeOption(download, &node);
  download->add_option("--out", out,
                       "Write it to this file (default: print; an existing file is "
                       "refused without --force)");
  download->add_flag("--force", force, "Replace the --out file if it exists");
  download->callback([] {
    if (!out.empty()) RefuseOverwrite(out, force, "--out");
    auto link = OpenLink(iface);
    host::BoardClient board(link.get(), static_cast<std::uint8_t>(node));
    IdentifyOrThrow(board);
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
  upload
      ->add_option("--timeout-ms", timeout_ms,
                   "Wait this long of the board's own time for its answer")
      ->check(InRange(10, 60000, "ms"))
      ->capture_default_str();
  upload->callback([] {
    const protocol::CalibrationRecord record = Load(file, "mjc cal upload");
    // Who answers first: a record sent to a node two boards answer for would calibrate
    // both, or whichever took it.
    {
      auto link = OpenLink(iface);
      host::BoardClient board(link.get(), static_cast<std::uint8_t>(node));
      IdentifyOrThrow(board, std::chrono::milliseconds(timeout_ms));
    }
    std::string why;
    const auto outcome = host::UploadCalibration(iface, node, record, timeout_ms, &why);
    const std::string who = "node " + std::to_string(node);
    switch (outcome.status) {
      case host::UploadStatus::kLinkFailed:
        throw Failure("cannot send to " + who + " on " + iface + ": " + why);
      case host::UploadStatus::kNoAnswer:
        throw Failure(Exit::kNoAnswer, who + " did not answer the upload (" + why + ")");
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
