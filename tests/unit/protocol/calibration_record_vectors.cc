// The calibration record on both platforms: a record round-trips; every single-byte
// corruption is refused (never accepted with other values); values the firmware's
// validators refuse come back as kOutOfRange with their reason; a version 1 record
// (written before the cable friction) still reads, with the friction not modelled.
#include <cstdint>

#include "mjc/protocol/calibration_record.h"
#include "vector_test.h"

namespace {

using namespace mjc;
using namespace mjc::protocol;

CalibrationRecord Sample() {
  CalibrationRecord r;
  r.backlash.c_right = Angle::FromDouble(0.0192);
  r.backlash.c_left = Angle::FromDouble(-0.0157);
  r.backlash.alpha = Scale::FromDouble(1.02);
  r.backlash.cable_friction = CableFrictionFromMilliNm(300);
  r.sea_stiffness = Stiffness::FromDouble(0.63);
  r.joint_zero_count = 8191;
  r.fit_rms_urad = 401;
  r.fit_lag_us = 1780;
  r.fitted_at_unix_s = 1795000000ull;
  return r;
}

MJC_VECTOR_TEST(CalibrationRecord, RoundTrips) {
  const CalibrationRecord sent = Sample();
  const auto bytes = EncodeCalibration(sent);
  CalibrationRecord got;
  std::uint8_t detail = 9;
  VT_EXPECT_TRUE(DecodeCalibration(bytes, &got, &detail) == CalibrationResult::kAccepted);
  VT_EXPECT_TRUE(got.backlash.c_right == sent.backlash.c_right);
  VT_EXPECT_TRUE(got.backlash.c_left == sent.backlash.c_left);
  VT_EXPECT_TRUE(got.backlash.alpha == sent.backlash.alpha);
  VT_EXPECT_TRUE(got.backlash.cable_friction == sent.backlash.cable_friction);
  VT_EXPECT_TRUE(got.sea_stiffness == sent.sea_stiffness);
  VT_EXPECT_EQ(got.joint_zero_count, 8191);
  VT_EXPECT_EQ(got.fit_lag_us, 1780u);
  VT_EXPECT_EQ(got.fitted_at_unix_s, 1795000000ull);
  VT_EXPECT_EQ(detail, 0);
}

MJC_VECTOR_TEST(CalibrationRecord, EverySingleByteCorruptionIsRefused) {
  const auto good = EncodeCalibration(Sample());
  int accepted = 0;
  for (std::size_t i = 0; i < good.size(); ++i) {
    for (int flip = 1; flip < 256; flip += 17) {
      auto bad = good;
      bad[i] = static_cast<std::uint8_t>(bad[i] ^ flip);
      CalibrationRecord out = Sample();
      out.fit_rms_urad = 12345;  // must survive a refusal
      std::uint8_t detail = 0;
      if (DecodeCalibration(bad, &out, &detail) == CalibrationResult::kAccepted)
        ++accepted;
      if (out.fit_rms_urad != 12345) ++accepted;
    }
  }
  VT_EXPECT_EQ(accepted, 0);
  CalibrationRecord out;
  std::uint8_t detail = 0;
  VT_EXPECT_TRUE(DecodeCalibration(std::span(good).first(47), &out, &detail) ==
                 CalibrationResult::kWrongSize);
}

MJC_VECTOR_TEST(CalibrationRecord, OutOfRangeValuesAreRefusedWithTheirReason) {
  CalibrationRecord r = Sample();
  r.backlash.c_left = Angle::FromDouble(0.05);  // above c_r
  CalibrationRecord out;
  std::uint8_t detail = 0;
  VT_EXPECT_TRUE(DecodeCalibration(EncodeCalibration(r), &out, &detail) ==
                 CalibrationResult::kOutOfRange);
  VT_EXPECT_EQ(detail, static_cast<int>(BacklashConfigError::kLeftAboveRight));
  r = Sample();
  r.backlash.c_right = Angle::FromDouble(0.7);  // 40°: no cable slack is that large
  VT_EXPECT_TRUE(DecodeCalibration(EncodeCalibration(r), &out, &detail) ==
                 CalibrationResult::kOutOfRange);
  VT_EXPECT_EQ(detail, static_cast<int>(BacklashConfigError::kOffsetOutOfRange));
  r = Sample();
  r.sea_stiffness = Stiffness{};
  VT_EXPECT_TRUE(DecodeCalibration(EncodeCalibration(r), &out, &detail) ==
                 CalibrationResult::kOutOfRange);
  VT_EXPECT_EQ(detail, 100);
  r = Sample();
  r.joint_zero_count = 20000;
  VT_EXPECT_TRUE(DecodeCalibration(EncodeCalibration(r), &out, &detail) ==
                 CalibrationResult::kOutOfRange);
  VT_EXPECT_EQ(detail, 101);
  r = Sample();
  r.backlash.cable_friction = CableFrictionFromMilliNm(5001);  // above 5 N·m
  VT_EXPECT_TRUE(DecodeCalibration(EncodeCalibration(r), &out, &detail) ==
                 CalibrationResult::kOutOfRange);
  VT_EXPECT_EQ(detail, static_cast<int>(BacklashConfigError::kFrictionOutOfRange));
}

// τ_f's wire unit: 1 mN·m = 2^24/1000 = 16777.216 LSB of Q7.24, to the nearest LSB,
// and back to the same mN·m; a friction off that grid goes to its nearest mN·m.
MJC_VECTOR_TEST(CalibrationRecord, CableFrictionTravelsInMilliNewtonMetres) {
  VT_EXPECT_EQ(CableFrictionFromMilliNm(0).raw(), 0);
  VT_EXPECT_EQ(CableFrictionFromMilliNm(1).raw(), 16777);
  VT_EXPECT_EQ(CableFrictionFromMilliNm(300).raw(), 5033165);  // 5,033,164.8
  VT_EXPECT_EQ(CableFrictionFromMilliNm(5000).raw(), 83886080);
  int round_trip_errors = 0;
  for (int m = 0; m <= 0xFFFF; m += 7) {
    const auto milli = static_cast<std::uint16_t>(m);
    if (CableFrictionMilliNm(CableFrictionFromMilliNm(milli)) != milli)
      ++round_trip_errors;
  }
  VT_EXPECT_EQ(round_trip_errors, 0);
  VT_EXPECT_EQ(CableFrictionMilliNm(Torque::FromRaw(8388)), 0);  // 0.49997 mN·m
  VT_EXPECT_EQ(CableFrictionMilliNm(Torque::FromRaw(8389)), 1);  // 0.50003 mN·m
  VT_EXPECT_EQ(CableFrictionMilliNm(-Torque::Epsilon()), 0);
}

// A version 1 record, laid out by hand from its documented layout (bytes 26..27
// reserved, 0), reads with the friction not modelled and every other field as written.
MJC_VECTOR_TEST(CalibrationRecord, VersionOneRecordsStillRead) {
  const CalibrationRecord sample = Sample();
  std::uint8_t b[kCalibrationRecordSize] = {};
  const auto put = [&](std::size_t at, std::uint64_t v, std::size_t n) {
    for (std::size_t i = 0; i < n; ++i)
      b[at + i] = static_cast<std::uint8_t>(v >> (8 * i));
  };
  put(0, 0x43434A4Du, 4);
  put(4, 1, 2);
  put(6, 36, 2);
  put(8, static_cast<std::uint32_t>(sample.backlash.c_right.raw()), 4);
  put(12, static_cast<std::uint32_t>(sample.backlash.c_left.raw()), 4);
  put(16, static_cast<std::uint32_t>(sample.backlash.alpha.raw()), 4);
  put(20, static_cast<std::uint32_t>(sample.sea_stiffness.raw()), 4);
  put(24, sample.joint_zero_count, 2);
  put(28, sample.fit_rms_urad, 4);
  put(32, sample.fit_lag_us, 4);
  put(36, sample.fitted_at_unix_s, 8);
  put(44, Crc32(std::span<const std::uint8_t>(b, 44)), 4);
  CalibrationRecord got;
  std::uint8_t detail = 9;
  VT_EXPECT_TRUE(DecodeCalibration(b, &got, &detail) == CalibrationResult::kAccepted);
  VT_EXPECT_TRUE(got.backlash.cable_friction == Torque{});
  VT_EXPECT_TRUE(got.backlash.c_right == sample.backlash.c_right);
  VT_EXPECT_TRUE(got.backlash.alpha == sample.backlash.alpha);
  VT_EXPECT_TRUE(got.sea_stiffness == sample.sea_stiffness);
  VT_EXPECT_EQ(got.joint_zero_count, sample.joint_zero_count);
  VT_EXPECT_EQ(got.fitted_at_unix_s, sample.fitted_at_unix_s);
  // Version 3 is nothing this board knows.
  put(4, 3, 2);
  put(44, Crc32(std::span<const std::uint8_t>(b, 44)), 4);
  VT_EXPECT_TRUE(DecodeCalibration(b, &got, &detail) ==
                 CalibrationResult::kUnsupportedVersion);
}

}  // namespace
