#include "mjc/protocol/calibration_record.h"

#include <algorithm>

#include "mjc/protocol/little_endian.h"

namespace mjc::protocol {
namespace {

std::int32_t GetI32(const std::uint8_t* p) {
  return static_cast<std::int32_t>(static_cast<std::uint32_t>(GetLe(p, 4)));
}

constexpr std::uint16_t kPayloadLength = 36;

}  // namespace

Torque CableFrictionFromMilliNm(std::uint16_t milli_nm) {
  // round(m·2^24/1000), in integers (m ≥ 0).
  const std::int64_t scaled = std::int64_t{milli_nm} << Torque::kFracBits;
  return Torque::FromRaw(static_cast<std::int32_t>((scaled + 500) / 1000));
}

std::uint16_t CableFrictionMilliNm(Torque friction) {
  const std::int64_t raw = std::max<std::int64_t>(friction.raw(), 0);
  const std::int64_t half = std::int64_t{1} << (Torque::kFracBits - 1);
  const std::int64_t milli = (raw * 1000 + half) >> Torque::kFracBits;
  return static_cast<std::uint16_t>(std::min<std::int64_t>(milli, 0xFFFF));
}

std::array<std::uint8_t, kCalibrationRecordSize> EncodeCalibration(
    const CalibrationRecord& r) {
  std::array<std::uint8_t, kCalibrationRecordSize> b{};
  PutLe(&b[0], kCalibrationMagic, 4);
  PutLe(&b[4], kCalibrationVersion, 2);
  PutLe(&b[6], kPayloadLength, 2);
  PutLe(&b[8], static_cast<std::uint32_t>(r.backlash.c_right.raw()), 4);
  PutLe(&b[12], static_cast<std::uint32_t>(r.backlash.c_left.raw()), 4);
  PutLe(&b[16], static_cast<std::uint32_t>(r.backlash.alpha.raw()), 4);
  PutLe(&b[20], static_cast<std::uint32_t>(r.sea_stiffness.raw()), 4);
  PutLe(&b[24], r.joint_zero_count, 2);
  PutLe(&b[26], CableFrictionMilliNm(r.backlash.cable_friction), 2);
  PutLe(&b[28], r.fit_rms_urad, 4);
  PutLe(&b[32], r.fit_lag_us, 4);
  PutLe(&b[36], r.fitted_at_unix_s, 8);
  PutLe(&b[44], Crc32(std::span<const std::uint8_t>(b.data(), 44)), 4);
  return b;
}

CalibrationResult DecodeCalibration(std::span<const std::uint8_t> b,
                                    CalibrationRecord* out, std::uint8_t* detail) {
  *detail = 0;
  if (b.size() != kCalibrationRecordSize) return CalibrationResult::kWrongSize;
  if (GetLe(&b[0], 4) != kCalibrationMagic) return CalibrationResult::kBadMagic;
  const std::uint64_t version = GetLe(&b[4], 2);
  if ((version != kCalibrationVersion && version != kCalibrationVersionWithoutFriction) ||
      GetLe(&b[6], 2) != kPayloadLength) {
    return CalibrationResult::kUnsupportedVersion;
  }
  if (GetLe(&b[44], 4) != Crc32(b.first(44))) return CalibrationResult::kBadCrc;
  CalibrationRecord r;
  r.backlash.c_right = Angle::FromRaw(GetI32(&b[8]));
  r.backlash.c_left = Angle::FromRaw(GetI32(&b[12]));
  r.backlash.alpha = Scale::FromRaw(GetI32(&b[16]));
  r.sea_stiffness = Stiffness::FromRaw(GetI32(&b[20]));
  r.joint_zero_count = static_cast<std::uint16_t>(GetLe(&b[24], 2));
  if (version == kCalibrationVersion) {
    r.backlash.cable_friction =
        CableFrictionFromMilliNm(static_cast<std::uint16_t>(GetLe(&b[26], 2)));
  }
  r.fit_rms_urad = static_cast<std::uint32_t>(GetLe(&b[28], 4));
  r.fit_lag_us = static_cast<std::uint32_t>(GetLe(&b[32], 4));
  r.fitted_at_unix_s = GetLe(&b[36], 8);
  const CalibrationError error =
      Validate(Calibration{r.backlash, r.sea_stiffness, r.joint_zero_count});
  if (error != CalibrationError::kOk) {
    *detail = static_cast<std::uint8_t>(error);
    return CalibrationResult::kOutOfRange;
  }
  *out = r;
  return CalibrationResult::kAccepted;
}

}  // namespace mjc::protocol
