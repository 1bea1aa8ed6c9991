// Calibrations on the host: the JSON file `mjc calibrate` writes and `mjc cal` reads
// (angles in degrees, for people), and the upload of a record to a board over ISO-TP.
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "mjc/protocol/calibration_record.h"

namespace mjc::host {

nlohmann::json CalibrationToJson(const protocol::CalibrationRecord& record);

// Reads and range-checks a calibration (the board's own checks, run here first): nullopt
// with the reason naming the field when it is missing, of the wrong type or out of
// range. The fit fields (fit_rms_urad, fit_lag_us, fitted_at_unix_s) are optional
// (absent: 0) but, when present, must be integers within their wire type's range.
// Never throws.
std::optional<protocol::CalibrationRecord> CalibrationFromJson(const nlohmann::json& json,
                                                               std::string* why);

struct UploadOutcome {
  bool answered = false;  // false: no reply (the node is absent or silent)
  protocol::CalibrationResult result = protocol::CalibrationResult::kAccepted;
  std::uint8_t detail = 0;
  double elapsed_ms = 0;
};

// Uploads `record` to `node` on `iface` (ISO-TP on the node's 0x3E/0x3F ids) and waits
// up to timeout_ms for the board's answer. nullopt with the reason when the interface
// cannot be opened.
std::optional<UploadOutcome> UploadCalibration(const std::string& iface, int node,
                                               const protocol::CalibrationRecord& record,
                                               int timeout_ms, std::string* why);

// Reads the calibration in force back from a board (its read-only calibration
// parameters); nullopt with the reason when it does not answer or is uncalibrated.
std::optional<protocol::CalibrationRecord> DownloadCalibration(const std::string& iface,
                                                               int node,
                                                               std::string* why);

// "accepted", "refused: bad CRC", … for messages.
std::string DescribeCalibrationResult(protocol::CalibrationResult result,
                                      std::uint8_t detail);

}  // namespace mjc::host
