// Any bytes as a calibration record: decoding never crashes, and an accepted record
// re-encodes to the same bytes (nothing is accepted that the board would not write).
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
  // Bytes 26..27 are reserved and not compared; everything else must match.
  for (std::size_t i = 0; i < again.size(); ++i) {
    if ((i < 26 || i > 27) && again[i] != data[i]) __builtin_trap();
  }
  return 0;
}
