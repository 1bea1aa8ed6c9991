// Any text as a plant parameter file and as a calibration file: a clear refusal or a
// validated result, never a crash or an uncaught exception.
#include <cstdint>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>

#include "mjc/host/calibration_io.h"
#include "mjc/plant/params.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    mjc::plant::ParsePlantParams(text, "<fuzz>");
  } catch (const std::runtime_error&) {
    // refused with a reason: fine
  }
  const auto json = nlohmann::json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (!json.is_discarded() && json.is_object()) {
    std::string why;
    const auto r = mjc::host::CalibrationFromJson(json, &why);
    if (!r && why.empty()) __builtin_trap();  // a refusal always says why
  }
  return 0;
}
