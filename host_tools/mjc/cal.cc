// mjc cal show|upload: a calibration file, and its upload to a board over ISO-TP.
#include <cstdio>
#include <fstream>

#include "commands.h"
#include "mjc/host/calibration_io.h"

namespace mjc::cli {

void AddCal(CLI::App& app, int* status) {
  auto* cal = app.add_subcommand("cal", "Show, upload or download a calibration");
  cal->require_subcommand(1);
  static std::string file, iface = "vcan0";
  static int node = 1, timeout_ms = 1000;

  auto load = [](std::optional<protocol::CalibrationRecord>* out) {
    std::ifstream in(file);
    if (!in) {
      std::fprintf(stderr, "mjc cal: cannot read %s\n", file.c_str());
      return false;
    }
    nlohmann::json j;
    try {
      in >> j;
    } catch (const std::exception& e) {
      std::fprintf(stderr, "mjc cal: %s is not JSON: %s\n", file.c_str(), e.what());
      return false;
    }
    std::string why;
    *out = host::CalibrationFromJson(j, &why);
    if (!*out) std::fprintf(stderr, "mjc cal: %s: %s\n", file.c_str(), why.c_str());
    return out->has_value();
  };

  auto* show =
      cal->add_subcommand("show", "Print a calibration file after the board's checks");
  show->add_option("file", file, "Calibration JSON (as mjc calibrate writes)")
      ->required();
  show->callback([status, load] {
    std::optional<protocol::CalibrationRecord> r;
    if (!load(&r)) {
      *status = 1;
      return;
    }
    std::printf("%s\n", host::CalibrationToJson(*r).dump(2).c_str());
    *status = 0;
  });

  auto* download = cal->add_subcommand("download", "Read a board's calibration back");
  download->add_option("--iface", iface, "CAN interface")->capture_default_str();
  download->add_option("--node", node, "Node id")
      ->check(CLI::Range(1, 8))
      ->capture_default_str();
  static std::string out;
  download->add_option("--out", out, "Write it to this file (default: print)");
  download->callback([status] {
    std::string why;
    const auto r = host::DownloadCalibration(iface, node, &why);
    if (!r) {
      std::fprintf(stderr, "mjc cal download: %s\n", why.c_str());
      *status = 3;
      return;
    }
    const std::string text = host::CalibrationToJson(*r).dump(2);
    if (out.empty()) {
      std::printf("%s\n", text.c_str());
    } else {
      std::ofstream(out) << text << '\n';
    }
    *status = 0;
  });

  auto* upload =
      cal->add_subcommand("upload", "Upload a calibration file to a board (ISO-TP)");
  upload->add_option("file", file, "Calibration JSON")->required();
  upload->add_option("--iface", iface, "CAN interface")->capture_default_str();
  upload->add_option("--node", node, "Node id")
      ->check(CLI::Range(1, 8))
      ->capture_default_str();
  upload->add_option("--timeout-ms", timeout_ms, "Wait this long for the board's answer")
      ->check(CLI::Range(10, 60000))
      ->capture_default_str();
  upload->callback([status, load] {
    std::optional<protocol::CalibrationRecord> r;
    if (!load(&r)) {
      *status = 1;
      return;
    }
    std::string why;
    const auto outcome = host::UploadCalibration(iface, node, *r, timeout_ms, &why);
    if (!outcome) {
      std::fprintf(stderr, "mjc cal upload: %s\n", why.c_str());
      *status = 1;
    } else if (!outcome->answered) {
      std::fprintf(stderr, "mjc cal upload: node %d on %s did not answer (%s)\n", node,
                   iface.c_str(), why.c_str());
      *status = 3;
    } else if (outcome->result != protocol::CalibrationResult::kAccepted) {
      std::fprintf(
          stderr, "mjc cal upload: node %d refused it: %s\n", node,
          host::DescribeCalibrationResult(outcome->result, outcome->detail).c_str());
      *status = 4;
    } else {
      std::printf("node %d accepted the calibration (%.1f ms)\n", node,
                  outcome->elapsed_ms);
      *status = 0;
    }
  });
}

}  // namespace mjc::cli
