#include "mjc/host/calibration_io.h"

#include <chrono>
#include <cmath>
#include <limits>

#include "mjc/host/can_link.h"
#include "mjc/host/describe.h"
#include "mjc/host/units.h"
#include "mjc/protocol/can_frame.h"
#include "mjc/protocol/messages.h"

namespace mjc::host {

nlohmann::json CalibrationToJson(const protocol::CalibrationRecord& r) {
  return {{"c_right_deg", RadToDeg(r.backlash.c_right.ToDouble())},
          {"c_left_deg", RadToDeg(r.backlash.c_left.ToDouble())},
          {"alpha", r.backlash.alpha.ToDouble()},
          {"sea_stiffness_Nm_per_rad", r.sea_stiffness.ToDouble()},
          {"joint_zero_count", r.joint_zero_count},
          {"fit_rms_urad", r.fit_rms_urad},
          {"fit_lag_us", r.fit_lag_us},
          {"fitted_at_unix_s", r.fitted_at_unix_s}};
}

std::optional<protocol::CalibrationRecord> CalibrationFromJson(const nlohmann::json& j,
                                                               std::string* why) {
  protocol::CalibrationRecord r;
  auto number = [&](const char* key, double* out) {
    if (!j.contains(key) || !j[key].is_number()) {
      *why = std::string("calibration: field '") + key + "' missing or not a number";
      return false;
    }
    *out = j[key].get<double>();
    if (!std::isfinite(*out)) {
      *why = std::string("calibration: field '") + key + "' is not finite";
      return false;
    }
    return true;
  };
  // An integer field in 0..max, as the record's unsigned wire fields hold them; absent
  // is 0 unless required.
  auto integer = [&](const char* key, std::uint64_t max, bool required, auto* out) {
    *out = 0;
    if (!j.contains(key) && !required) return true;
    const bool in_range =
        j.contains(key) && j[key].is_number_integer() &&
        (j[key].is_number_unsigned() || j[key].get<std::int64_t>() >= 0) &&
        j[key].get<std::uint64_t>() <= max;
    if (!in_range) {
      *why = std::string("calibration: field '") + key + "' must be an integer in 0.." +
             std::to_string(max);
      return false;
    }
    *out = static_cast<std::remove_pointer_t<decltype(out)>>(j[key].get<std::uint64_t>());
    return true;
  };
  using U32 = std::numeric_limits<std::uint32_t>;
  double c_right = 0, c_left = 0, alpha = 0, stiffness = 0;
  if (!number("c_right_deg", &c_right) || !number("c_left_deg", &c_left) ||
      !number("alpha", &alpha) || !number("sea_stiffness_Nm_per_rad", &stiffness) ||
      !integer("joint_zero_count", 16383, true, &r.joint_zero_count) ||
      !integer("fit_rms_urad", U32::max(), false, &r.fit_rms_urad) ||
      !integer("fit_lag_us", U32::max(), false, &r.fit_lag_us) ||
      !integer("fitted_at_unix_s", std::numeric_limits<std::uint64_t>::max(), false,
               &r.fitted_at_unix_s)) {
    return std::nullopt;
  }
  r.backlash.c_right = Angle::Quantize(DegToRad(c_right));
  r.backlash.c_left = Angle::Quantize(DegToRad(c_left));
  r.backlash.alpha = Scale::Quantize(alpha);
  r.sea_stiffness = Stiffness::Quantize(stiffness);
  // The board's checks, run here first, so a bad file never reaches the bus.
  const auto bytes = protocol::EncodeCalibration(r);
  protocol::CalibrationRecord checked;
  std::uint8_t detail = 0;
  const auto result = protocol::DecodeCalibration(bytes, &checked, &detail);
  if (result != protocol::CalibrationResult::kAccepted) {
    *why = "calibration refused: " + DescribeCalibrationResult(result, detail);
    return std::nullopt;
  }
  return checked;
}

UploadOutcome UploadCalibration(const std::string& iface, int node,
                                const protocol::CalibrationRecord& record, int timeout_ms,
                                std::string* why) {
  using protocol::Function;
  const auto n = static_cast<std::uint8_t>(node);
  UploadOutcome out;
  auto link = IsoTpLink::Open(
      iface, protocol::MakeId(static_cast<std::uint8_t>(Function::kIsoTpToBoard), n),
      protocol::MakeId(static_cast<std::uint8_t>(Function::kIsoTpFromBoard), n), why);
  const auto t0 = std::chrono::steady_clock::now();
  if (!link || !link->Send(protocol::EncodeCalibration(record), why)) {
    out.status = UploadStatus::kLinkFailed;
    return out;
  }
  const auto reply = link->Receive(timeout_ms, why);
  out.elapsed_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0)
          .count();
  if (!reply) {
    out.status = UploadStatus::kNoAnswer;
    return out;
  }
  if (reply->size() != 2) {
    out.status = UploadStatus::kMalformedReply;
    *why = "node " + std::to_string(node) + " answered with " +
           std::to_string(reply->size()) + " bytes, not [result, detail]";
    return out;
  }
  out.status = UploadStatus::kAnswered;
  out.result = static_cast<protocol::CalibrationResult>((*reply)[0]);
  out.detail = (*reply)[1];
  return out;
}

std::optional<BoardCalibration> ReadCalibration(BoardClient& board, std::string* why) {
  using protocol::ParamId;
  std::int32_t value[6] = {};
  const ParamId ids[6] = {ParamId::kCalibrated,           ParamId::kCalibrationRight,
                          ParamId::kCalibrationLeft,      ParamId::kCalibrationAlpha,
                          ParamId::kCalibrationStiffness, ParamId::kCalibrationJointZero};
  for (int i = 0; i < 6; ++i) {
    const auto v = board.ReadParam(ids[i], 500, why);
    if (!v) return std::nullopt;
    value[i] = *v;
  }
  if (value[5] < 0 || value[5] > 16383) {
    *why = "node " + std::to_string(board.node()) + " reports joint zero count " +
           std::to_string(value[5]) + ", outside 0..16383";
    return std::nullopt;
  }
  BoardCalibration out;
  out.calibrated = value[0] == 1;
  out.record.backlash.c_right = Angle::FromRaw(value[1]);
  out.record.backlash.c_left = Angle::FromRaw(value[2]);
  out.record.backlash.alpha = Scale::FromRaw(value[3]);
  out.record.sea_stiffness = Stiffness::FromRaw(value[4]);
  out.record.joint_zero_count = static_cast<std::uint16_t>(value[5]);
  return out;
}

}  // namespace mjc::host
