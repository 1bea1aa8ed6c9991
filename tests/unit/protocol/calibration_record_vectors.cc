// The calibration record on both platforms: a record round-trips; every single-byte
// corruption is refused (never accepted with other values); values the firmware's
// validators refuse come back as kOutOfRange with their reason.
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
}

}  // namespace
