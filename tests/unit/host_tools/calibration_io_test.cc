// The calibration file `mjc calibrate` writes and `mjc cal` reads
// (mjc/host/calibration_io.h): degrees in the file against the record's fixed point,
// every field range-checked, unknown keys named, implausible values warned about, a
// refusal never an exception. (The upload and the read-back need a board on a bus:
// tests/kernel.)
#include "mjc/host/calibration_io.h"

#include <gtest/gtest.h>

#include <iterator>
#include <nlohmann/json.hpp>
#include <numbers>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace mjc::host {
namespace {

nlohmann::json GoodCalibrationJson() {
  return {{"c_right_deg", 1.1},
          {"c_left_deg", -0.9},
          {"alpha", 1.0},
          {"sea_stiffness_Nm_per_rad", 0.63},
          {"joint_zero_count", 123},
          {"fit_rms_urad", 250},
          {"fit_lag_us", 4000},
          {"fitted_at_unix_s", 1700000000}};
}

TEST(CalibrationFile, RoundTripsThroughJson) {
  std::string why;
  const auto record = CalibrationFromJson(GoodCalibrationJson(), &why);
  ASSERT_TRUE(record) << why;
  EXPECT_EQ(record->joint_zero_count, 123);
  EXPECT_EQ(record->fit_rms_urad, 250u);
  EXPECT_EQ(record->fit_lag_us, 4000u);
  EXPECT_EQ(record->fitted_at_unix_s, 1700000000u);
  const auto again = CalibrationFromJson(CalibrationToJson(*record), &why);
  ASSERT_TRUE(again) << why;
  EXPECT_EQ(again->backlash.c_right, record->backlash.c_right);
  EXPECT_EQ(again->backlash.c_left, record->backlash.c_left);
  EXPECT_EQ(again->fitted_at_unix_s, record->fitted_at_unix_s);
}

// Degrees in the file, the firmware's fixed point in the record: the conversion
// against the definitions (π/180, the formats' resolutions), both ways.
TEST(CalibrationFile, DegreesInTheFileRadiansInTheRecord) {
  std::string why;
  const auto record = CalibrationFromJson(GoodCalibrationJson(), &why);
  ASSERT_TRUE(record) << why;
  constexpr double kRadPerDeg = std::numbers::pi / 180.0;
  EXPECT_NEAR(record->backlash.c_right.ToDouble(), 1.1 * kRadPerDeg,
              Angle::Epsilon().ToDouble());
  EXPECT_NEAR(record->backlash.c_left.ToDouble(), -0.9 * kRadPerDeg,
              Angle::Epsilon().ToDouble());
  EXPECT_NEAR(record->backlash.alpha.ToDouble(), 1.0, Scale::Epsilon().ToDouble());
  EXPECT_NEAR(record->sea_stiffness.ToDouble(), 0.63, Stiffness::Epsilon().ToDouble());
  const nlohmann::json j = CalibrationToJson(*record);
  for (const std::string_view key : kCalibrationKeys) {
    EXPECT_TRUE(j.contains(std::string(key))) << key;
  }
  EXPECT_EQ(j.size(), std::size(kCalibrationKeys));
  EXPECT_NEAR(j["c_right_deg"].get<double>(), 1.1,
              Angle::Epsilon().ToDouble() / kRadPerDeg);
  EXPECT_NEAR(j["c_left_deg"].get<double>(), -0.9,
              Angle::Epsilon().ToDouble() / kRadPerDeg);
  EXPECT_EQ(j["joint_zero_count"].get<int>(), 123);
}

TEST(CalibrationFile, FitFieldsAreOptional) {
  nlohmann::json j = GoodCalibrationJson();
  for (const char* key : {"fit_rms_urad", "fit_lag_us", "fitted_at_unix_s"}) j.erase(key);
  std::string why;
  const auto record = CalibrationFromJson(j, &why);
  ASSERT_TRUE(record) << why;
  EXPECT_EQ(record->fit_rms_urad, 0u);
  EXPECT_EQ(record->fitted_at_unix_s, 0u);
}

TEST(CalibrationFile, IntegersOutOfTheirWireRangeAreRefused) {
  struct Case {
    const char* key;
    nlohmann::json value;
  };
  const Case cases[] = {
      {"fit_rms_urad", -5},  // would wrap to 4294967291
      {"fit_rms_urad", 4294967296ull},
      {"fit_lag_us", 1.5},
      {"fit_lag_us", "4000"},  // a string: a type error inside nlohmann if not checked
      {"fitted_at_unix_s", -1},
      {"joint_zero_count", 16384},
      {"joint_zero_count", nullptr},
  };
  for (const Case& c : cases) {
    nlohmann::json j = GoodCalibrationJson();
    j[c.key] = c.value;
    std::string why;
    std::optional<protocol::CalibrationRecord> record;
    EXPECT_NO_THROW(record = CalibrationFromJson(j, &why)) << c.key << " = " << c.value;
    EXPECT_FALSE(record) << c.key << " = " << c.value;
    EXPECT_NE(why.find(std::string("'") + c.key + "' must be an integer in 0.."),
              std::string::npos)
        << why;
  }
  nlohmann::json largest = GoodCalibrationJson();
  largest["fit_rms_urad"] = 4294967295u;
  std::string why;
  const auto record = CalibrationFromJson(largest, &why);
  ASSERT_TRUE(record) << why;
  EXPECT_EQ(record->fit_rms_urad, 4294967295u);
}

TEST(CalibrationFile, UnknownKeysAreRefusedAndNamed) {
  nlohmann::json j = GoodCalibrationJson();
  j.erase("c_right_deg");
  j["c_rigth_deg"] = 1.1;
  std::string why;
  EXPECT_FALSE(CalibrationFromJson(j, &why));
  EXPECT_EQ(why, "calibration: unknown key 'c_rigth_deg' (did you mean 'c_right_deg'?)");
  j = GoodCalibrationJson();
  j["operator"] = "ana";
  EXPECT_FALSE(CalibrationFromJson(j, &why));
  EXPECT_EQ(why.rfind("calibration: unknown key 'operator' (known: c_right_deg, ", 0), 0u)
      << why;
  EXPECT_FALSE(CalibrationFromJson(nlohmann::json::array({1, 2}), &why));
  EXPECT_EQ(why, "calibration: the top level must be an object");
}

TEST(CalibrationFile, ImplausibleValuesAreKeptWithAWarningEach) {
  nlohmann::json j = GoodCalibrationJson();
  std::vector<std::string> warnings;
  std::string why;
  ASSERT_TRUE(CalibrationFromJson(j, &why, &warnings)) << why;
  EXPECT_TRUE(warnings.empty());
  // 0.0192 rad typed as degrees is plausible; 19.2 (degrees of a radian slip) is not.
  j["c_right_deg"] = 19.2;
  j["sea_stiffness_Nm_per_rad"] = 63.0;
  ASSERT_TRUE(CalibrationFromJson(j, &why, &warnings)) << why;
  ASSERT_EQ(warnings.size(), 2u);
  EXPECT_EQ(warnings[0].rfind("calibration: c_right_deg = 19.2° is beyond the "
                              "plausible ±10°",
                              0),
            0u)
      << warnings[0];
  EXPECT_NE(warnings[1].find("sea_stiffness_Nm_per_rad = 63 is outside the plausible "
                             "[0.063, 6.3] N·m/rad"),
            std::string::npos)
      << warnings[1];
  // Beyond what the board accepts: refused, not warned about.
  j["c_right_deg"] = 30.0;
  warnings.clear();
  EXPECT_FALSE(CalibrationFromJson(j, &why, &warnings));
  EXPECT_NE(why.find("outside ±28.6°"), std::string::npos) << why;
}

}  // namespace
}  // namespace mjc::host
