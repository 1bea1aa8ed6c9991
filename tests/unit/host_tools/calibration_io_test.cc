// The calibration file `mjc calibrate` writes and `mjc cal` reads
// (mjc/host/calibration_io.h): degrees in the file against the record's fixed point,
// every field range-checked, unknown keys named, implausible values warned about, a
// refusal never an exception. (The upload and the read-back need a board on a bus:
// tests/kernel.)
#include "mjc/host/calibration_io.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
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

// "cable_friction_Nm" is optional (absent in a file written before it existed: not
// modelled), held on the record's mN·m grid, and refused outside [0, 5] N·m.
TEST(CalibrationFile, CableFrictionIsOptionalAndChecked) {
  std::string why;
  auto record = CalibrationFromJson(GoodCalibrationJson(), &why);
  ASSERT_TRUE(record) << why;
  EXPECT_EQ(record->backlash.cable_friction, Torque{});
  EXPECT_EQ(CalibrationToJson(*record)["cable_friction_Nm"].get<double>(), 0.0);
  nlohmann::json j = GoodCalibrationJson();
  j["cable_friction_Nm"] = 0.3;
  record = CalibrationFromJson(j, &why);
  ASSERT_TRUE(record) << why;
  EXPECT_EQ(record->backlash.cable_friction, protocol::CableFrictionFromMilliNm(300));
  EXPECT_EQ(CalibrationToJson(*record)["cable_friction_Nm"].get<double>(), 0.3);
  for (const double bad : {-0.001, 5.001}) {
    j["cable_friction_Nm"] = bad;
    EXPECT_FALSE(CalibrationFromJson(j, &why));
    EXPECT_NE(why.find("'cable_friction_Nm'"), std::string::npos) << why;
    EXPECT_NE(why.find("outside [0, 5"), std::string::npos) << why;
  }
  j["cable_friction_Nm"] = "0.3";
  EXPECT_FALSE(CalibrationFromJson(j, &why));
  EXPECT_NE(why.find("'cable_friction_Nm' missing or not a number"), std::string::npos)
      << why;
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
  // 25° is beyond a cable's slack (degrees of a radian slip?).
  j["c_right_deg"] = 25.0;
  j["sea_stiffness_Nm_per_rad"] = 63.0;
  ASSERT_TRUE(CalibrationFromJson(j, &why, &warnings)) << why;
  ASSERT_EQ(warnings.size(), 2u);
  EXPECT_EQ(warnings[0].rfind("calibration: c_right_deg = 25° is beyond the "
                              "plausible ±20°",
                              0),
            0u)
      << warnings[0];
  EXPECT_NE(warnings[1].find("sea_stiffness_Nm_per_rad = 63 is outside the plausible "
                             "[0.063, 6.3] N·m/rad"),
            std::string::npos)
      << warnings[1];
  // The paper's 1.1° and -0.9° typed in radians: below two counts of the 14-bit joint
  // encoder (2·360°/16384 = 0.0439°), each side named with the likely slip.
  j = GoodCalibrationJson();
  j["c_right_deg"] = 0.0192;
  j["c_left_deg"] = -0.0157;
  warnings.clear();
  ASSERT_TRUE(CalibrationFromJson(j, &why, &warnings)) << why;
  ASSERT_EQ(warnings.size(), 2u);
  EXPECT_EQ(warnings[0],
            "calibration: c_right_deg = 0.0192° is below two counts of the 14-bit joint "
            "encoder (0.044°), less slack than a sweep can resolve: radians written in a "
            "degree field? (0.0192 rad is 1.10°)");
  EXPECT_NE(warnings[1].find("c_left_deg = -0.0157° is below two counts"),
            std::string::npos)
      << warnings[1];
  // Two counts and a little more: plausible.
  j["c_right_deg"] = 0.045;
  j["c_left_deg"] = -0.045;
  warnings.clear();
  ASSERT_TRUE(CalibrationFromJson(j, &why, &warnings)) << why;
  EXPECT_TRUE(warnings.empty()) << warnings.front();
  j = GoodCalibrationJson();
  j["sea_stiffness_Nm_per_rad"] = 63.0;
  // Beyond what the board accepts: refused, not warned about.
  j["c_right_deg"] = 30.0;
  warnings.clear();
  EXPECT_FALSE(CalibrationFromJson(j, &why, &warnings));
  EXPECT_NE(why.find("outside ±28.6°"), std::string::npos) << why;
}

// FitSweep: a calibration sweep to the record `mjc calibrate` uploads. The reference is
// a play operator written here in double precision (θ̃ = clamp(θ̃, α(θ_m − c_r),
// α(θ_m − c_l))) on an increasing-amplitude sweep at 1 kHz, as the board records it.
struct SyntheticSweep {
  std::vector<double> motor_rad, joint_rad;
};

SyntheticSweep PlaySweep(double c_right_rad, double c_left_rad, double alpha) {
  SyntheticSweep s;
  constexpr double kRateHz = 1000, kFrequencyHz = 0.5, kEndAmplitudeRad = 0.5;
  constexpr int kCycles = 10;
  const int n = static_cast<int>(kCycles / kFrequencyHz * kRateHz);
  double held = 0;
  for (int i = 0; i < n; ++i) {
    const double t = i / kRateHz;
    const double amplitude = kEndAmplitudeRad * (i + 1) / n;
    const double motor = amplitude * std::sin(2 * std::numbers::pi * kFrequencyHz * t);
    held = std::clamp(held, alpha * (motor - c_right_rad), alpha * (motor - c_left_rad));
    s.motor_rad.push_back(motor);
    s.joint_rad.push_back(held);
  }
  return s;
}

TEST(FitSweep, WithoutADescriptionTheBoardKeepsItsStiffnessAndZero) {
  // Setup: a board holding K = 0.5 N·m/rad, a cable friction of 0.25 N·m and zero
  // count 321; the cable's slack.
  const SyntheticSweep sweep = PlaySweep(1.2 * kDeg, -0.8 * kDeg, 1.0);
  protocol::CalibrationRecord held;
  held.sea_stiffness = Stiffness::FromDouble(0.5);
  held.backlash.cable_friction = protocol::CableFrictionFromMilliNm(250);
  held.joint_zero_count = 321;
  held.fitted_at_unix_s = 42;

  // Exercise.
  const SweepCalibration out =
      FitSweep(sweep.motor_rad, sweep.joint_rad, 1000, held, nullptr, false);

  // Verify: the slack to well inside a joint-encoder count (0.022°), α = 1, the
  // board's own stiffness, zero and date; the fit's RMS and lag in the record.
  ASSERT_TRUE(out.record) << out.why;
  EXPECT_NEAR(out.record->backlash.c_right.ToDouble(), 1.2 * kDeg, 0.002 * kDeg);
  EXPECT_NEAR(out.record->backlash.c_left.ToDouble(), -0.8 * kDeg, 0.002 * kDeg);
  EXPECT_DOUBLE_EQ(out.record->backlash.alpha.ToDouble(), 1.0);
  EXPECT_EQ(out.record->sea_stiffness, held.sea_stiffness);
  EXPECT_EQ(out.record->backlash.cable_friction, held.backlash.cable_friction);
  EXPECT_EQ(out.record->joint_zero_count, 321);
  EXPECT_EQ(out.record->fitted_at_unix_s, 42u);
  EXPECT_EQ(out.record->fit_rms_urad,
            static_cast<std::uint32_t>(std::lround(out.fit.rms_error_rad * 1e6)));
  EXPECT_EQ(out.record->fit_lag_us,
            static_cast<std::uint32_t>(std::lround(out.fit.lag_s * 1e6)));
  EXPECT_LT(out.fit.rms_error_rad, 1e-5);
}

TEST(FitSweep, ADescriptionGivesAlphaStiffnessAndZeroAndShiftsTheAngles) {
  // Setup: a joint with α = 1.25 (r_m 12.5 mm, r_j 10 mm) and its encoder zero at
  // 1000 counts; the board still holds zero 900, so it measured every joint angle
  // 100 counts (100·2π/16384 rad) above the joint's own zero.
  RobotDescription robot;
  robot.motor_pulley_radius_m = 0.0125;
  robot.joint_pulley_radius_m = 0.01;
  robot.spring_rate_N_per_m = 4000;
  robot.joint_zero_count = 1000;
  robot.cable_friction_Nm = 0.3;
  SyntheticSweep sweep = PlaySweep(1.0 * kDeg, -0.6 * kDeg, 1.25);
  const double offset_rad = 100 * 2 * std::numbers::pi / 16384;
  for (double& j : sweep.joint_rad) j += offset_rad;
  protocol::CalibrationRecord held;
  held.joint_zero_count = 900;

  // Exercise.
  const SweepCalibration out =
      FitSweep(sweep.motor_rad, sweep.joint_rad, 1000, held, &robot, false);

  // Verify: the slack of the joint's own angles, α, K = 2·k·r_j² = 0.8 N·m/rad and
  // τ_f from the description (quantised to the record's formats), its zero count.
  ASSERT_TRUE(out.record) << out.why;
  EXPECT_NEAR(out.record->backlash.c_right.ToDouble(), 1.0 * kDeg, 0.002 * kDeg);
  EXPECT_NEAR(out.record->backlash.c_left.ToDouble(), -0.6 * kDeg, 0.002 * kDeg);
  EXPECT_NEAR(out.record->backlash.alpha.ToDouble(), 1.25, 1e-8);
  EXPECT_NEAR(out.record->sea_stiffness.ToDouble(), 0.8, 1e-7);
  EXPECT_EQ(out.record->backlash.cable_friction, protocol::CableFrictionFromMilliNm(300));
  EXPECT_EQ(out.record->joint_zero_count, 1000);
}

TEST(FitSweep, AJointThatNeverMovesGivesNoRecordAndSaysWhy) {
  // Setup: the motor sweeps, the joint reads the same angle throughout.
  SyntheticSweep sweep = PlaySweep(1.0 * kDeg, -1.0 * kDeg, 1.0);
  std::fill(sweep.joint_rad.begin(), sweep.joint_rad.end(), 0.0);

  // Exercise.
  const SweepCalibration out =
      FitSweep(sweep.motor_rad, sweep.joint_rad, 1000, {}, nullptr, false);

  // Verify.
  EXPECT_FALSE(out.record);
  EXPECT_FALSE(out.why.empty());
}

}  // namespace
}  // namespace mjc::host
