// Any bytes as a calibration record: decoding never crashes, and an accepted record
// re-encodes to the same bytes (nothing is accepted that the board would not write). A
// version 1 record is re-encoded as version 2: the same but for the version, the
// friction (reserved in version 1, read as 0 whatever it held) and the CRC.
#include <cstdint>
#include <cstring>

#include "mjc/protocol/calibration_record.h"

using namespace mjc::protocol;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  CalibrationRecord r;
  std::uint8_t detail = 0;
  if (DecodeCalibration({data, size}, &r, &detail) != CalibrationResult::kAccepted)
    return 0;
  const auto again = EncodeCalibration(r);
  const bool version_1 = data[4] == kCalibrationVersionWithoutFriction && data[5] == 0;
  if (version_1 && !(r.backlash.cable_friction == mjc::Torque{})) __builtin_trap();
  for (std::size_t i = 0; i < again.size(); ++i) {
    const bool rewritten = i == 4 || (i >= 26 && i <= 27) || i >= 44;
    if (version_1 && rewritten) continue;
    if (again[i] != data[i]) __builtin_trap();
  }
  return 0;
}
