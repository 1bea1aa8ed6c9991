// Any text as each file mjc trial, mjc calibrate and mjc report read beside the
// calibration and parameter files: windows.csv, run.json, a robot description, mjc's
// config file. A clear refusal or a result within what the reader promises, never a
// crash, an uncaught exception or a non-finite number let through.
#include <cmath>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>

#include "mjc/host/config.h"
#include "mjc/host/robot_description.h"
#include "mjc/host/run_record.h"
#include "mjc/host/trial_report.h"
#include "mjc/strict_json.h"

namespace {

bool Finite(const mjc::host::BoardWindow& w) {
  for (const double v :
       {w.eta_percent, w.loading_J, w.unloading_J, w.positive_J, w.negative_J,
        w.peak_power_W, w.peak_torque_Nm, w.stiffness_Nm_rad, w.damping_Nms_rad,
        w.offset_Nm, w.residual_rms_Nm}) {
    if (!std::isfinite(v)) return false;
  }
  return true;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  std::string why;
  // windows.csv: a refusal says why; what is accepted is finite, each trial's
  // amplitude within the protocol's range.
  if (const auto trials = mjc::host::ParseWindowsCsv(text, "<fuzz>", &why)) {
    for (const auto& t : *trials) {
      if (!(t.amplitude_deg >= 1 && t.amplitude_deg <= 90)) __builtin_trap();
      for (const auto& w : t.windows) {
        if (!Finite(w)) __builtin_trap();
      }
    }
  } else if (why.empty()) {
    __builtin_trap();
  }
  // run.json, through the strict parse its reader uses.
  try {
    const auto json = mjc::strict::ParseObject<nlohmann::json>(text, "<fuzz>");
    why.clear();
    const auto run = mjc::host::RunRecordFromJson(json, &why);
    if (!run && why.empty()) __builtin_trap();
    // What is accepted is written back as it was read.
    if (run && !mjc::host::RunRecordFromJson(mjc::host::RunRecordToJson(*run), &why)) {
      __builtin_trap();
    }
  } catch (const std::runtime_error&) {
    // not JSON, a key twice, not an object: refused with a reason
  }
  why.clear();
  if (!mjc::host::ParseRobotDescription(text, "<fuzz>", &why) && why.empty()) {
    __builtin_trap();
  }
  why.clear();
  if (!mjc::host::ParseToolConfig(text, "<fuzz>", &why) && why.empty()) __builtin_trap();
  return 0;
}
