// Robot descriptions (mjc/host/robot_description.h): the shipped files load, α and K
// follow from the parts by their formulas, every field is checked (missing, wrong type,
// unknown key with its nearest match, implausible value with the range named), and a
// refusal is never an exception. (That the default description agrees with the
// simulator's default plant is checked against the plant's own file in
// tests/sim/robot_joint_test.cc.)
#include "mjc/host/robot_description.h"

#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <numbers>
#include <string>

#include "mjc/host/joint_limits.h"

namespace mjc::host {
namespace {

const std::string kRobots = std::string(MJC_SOURCE_DIR) + "/robots/";

nlohmann::json RobotJson() {
  return nlohmann::json::parse(R"({
    "name": "index-mcp",
    "pulleys": {"motor_radius_m": 0.015, "joint_radius_m": 0.012},
    "springs": {"rate_N_per_m": 4000.0},
    "motor_encoder": {"counts_per_rev": 2048, "gear_ratio": 100.0, "count_at_zero": 7},
    "joint_encoder": {"counts_per_rev": 16384, "zero_count": 300},
    "limits": {"extension_deg": -30.0, "flexion_deg": 80.0, "torque_Nm": 0.8}
  })");
}

std::string RobotRefusal(const nlohmann::json& j) {
  std::string why;
  const auto robot = ParseRobotDescription(j.dump(), "test.json", &why);
  EXPECT_FALSE(robot) << "accepted: " << j.dump();
  return why;
}

TEST(RobotDescription, ReadsEveryFieldAndDerivesAlphaAndStiffness) {
  std::string why;
  const auto robot = ParseRobotDescription(RobotJson().dump(), "test.json", &why);
  ASSERT_TRUE(robot) << why;
  EXPECT_EQ(robot->name, "index-mcp");
  EXPECT_EQ(robot->motor_counts_per_rev, 2048);
  EXPECT_EQ(robot->gear_ratio, 100.0);
  EXPECT_EQ(robot->motor_count_at_zero, 7);
  EXPECT_EQ(robot->joint_zero_count, 300);
  EXPECT_EQ(robot->extension_limit_deg, -30.0);
  EXPECT_EQ(robot->flexion_limit_deg, 80.0);
  EXPECT_EQ(robot->torque_limit_Nm, 0.8);
  // By hand: 15 / 12 = 1.25; 2 · 4000 N/m · (0.012 m)² = 1.152 N·m/rad.
  EXPECT_DOUBLE_EQ(robot->Alpha(), 1.25);
  EXPECT_DOUBLE_EQ(robot->SeaStiffness(), 1.152);
  const std::string line = DescribeRobot(*robot, "test.json");
  EXPECT_NE(line.find("index-mcp (test.json): α = 1.2500"), std::string::npos) << line;
  EXPECT_NE(line.find("K = 1.1520 N·m/rad"), std::string::npos) << line;
  // No "cable": the friction is not modelled.
  EXPECT_EQ(robot->cable_friction_Nm, 0.0);
  EXPECT_NE(line.find("cable friction not modelled"), std::string::npos) << line;
}

TEST(RobotDescription, ReadsTheCableFriction) {
  nlohmann::json j = RobotJson();
  j["cable"] = {{"friction_Nm", 0.2345}};
  std::string why;
  const auto robot = ParseRobotDescription(j.dump(), "test.json", &why);
  ASSERT_TRUE(robot) << why;
  EXPECT_EQ(robot->cable_friction_Nm, 0.2345);
  const std::string line = DescribeRobot(*robot, "test.json");
  EXPECT_NE(line.find("cable friction 0.234 N·m"), std::string::npos) << line;
  // The record carries it on its mN·m grid: 0.2345 N·m → 235 mN·m (half away from 0).
  protocol::CalibrationRecord record;
  UseRobotJoint(*robot, &record);
  EXPECT_EQ(protocol::CableFrictionMilliNm(record.backlash.cable_friction), 235);
  EXPECT_EQ(record.backlash.cable_friction, protocol::CableFrictionFromMilliNm(235));
  j["cable"] = {{"friction_Nm", 5.5}};
  EXPECT_EQ(RobotRefusal(j),
            "test.json: field 'cable.friction_Nm' = 5.5 is outside the plausible [0, 5] "
            "N·m");
  j["cable"] = {{"friction_Nm", -0.1}};
  EXPECT_NE(RobotRefusal(j).find("'cable.friction_Nm' = -0.1 is outside"),
            std::string::npos);
  j["cable"] = {{"friction", 0.3}};
  EXPECT_NE(RobotRefusal(j).find("friction_Nm"), std::string::npos);
}

TEST(RobotDescription, ShippedFilesLoad) {
  for (const char* file : {"maestro-default.json", "example-alpha-1.25.json"}) {
    std::string why;
    EXPECT_TRUE(LoadRobotDescription(kRobots + file, &why)) << why;
  }
  std::string why;
  const auto example = LoadRobotDescription(kRobots + "example-alpha-1.25.json", &why);
  ASSERT_TRUE(example) << why;
  EXPECT_DOUBLE_EQ(example->Alpha(), 1.25);
  EXPECT_NEAR(example->SeaStiffness(), 1.152, 1e-12);
}

TEST(RobotDescription, RefusesMissingWrongTypedAndUnknownFields) {
  nlohmann::json j = RobotJson();
  j["pulleys"].erase("joint_radius_m");
  EXPECT_EQ(RobotRefusal(j), "test.json: field 'pulleys.joint_radius_m' is missing");
  j = RobotJson();
  j["springs"]["rate_N_per_m"] = "4000";
  EXPECT_EQ(RobotRefusal(j), "test.json: field 'springs.rate_N_per_m' must be a number");
  j = RobotJson();
  j["motor_encoder"]["counts_per_rev"] = 2048.5;
  EXPECT_EQ(RobotRefusal(j),
            "test.json: field 'motor_encoder.counts_per_rev' must be an integer");
  j = RobotJson();
  j["springs"]["rate_N_per_mm"] = 4.0;
  EXPECT_EQ(RobotRefusal(j),
            "test.json: unknown key 'springs.rate_N_per_mm' (did you mean "
            "'springs.rate_N_per_m'?)");
  j = RobotJson();
  j["pulley"] = j["pulleys"];
  EXPECT_NE(RobotRefusal(j).find("unknown key 'pulley' (did you mean 'pulleys'?)"),
            std::string::npos);
  j = RobotJson();
  j["limits"] = 1.0;
  EXPECT_EQ(RobotRefusal(j), "test.json: field 'limits' must be an object");
  j = RobotJson();
  j["name"] = "index mcp";
  EXPECT_NE(RobotRefusal(j).find("field 'name'"), std::string::npos);
  EXPECT_NE(RobotRefusal(nlohmann::json::array()).find("top level must be an object"),
            std::string::npos);
  std::string why;
  EXPECT_FALSE(ParseRobotDescription("{\"name\": ", "test.json", &why));
  EXPECT_NE(why.find("not valid JSON"), std::string::npos) << why;
  EXPECT_FALSE(LoadRobotDescription(kRobots + "no-such-joint.json", &why));
  EXPECT_NE(why.find("cannot open the robot description"), std::string::npos) << why;
}

TEST(RobotDescription, RefusesImplausibleValuesNamingTheRange) {
  nlohmann::json j = RobotJson();
  j["pulleys"]["joint_radius_m"] = 12.0;  // mm written as m
  EXPECT_EQ(RobotRefusal(j),
            "test.json: field 'pulleys.joint_radius_m' = 12 is outside the plausible "
            "[0.002, 0.05] m");
  j = RobotJson();
  j["pulleys"]["motor_radius_m"] = 0.03;  // α = 2.5
  EXPECT_EQ(RobotRefusal(j),
            "test.json: field 'pulleys' give α = r_m / r_j = 2.5, outside the plausible "
            "[0.5, 2]");
  j = RobotJson();
  j["springs"]["rate_N_per_m"] = 30000.0;  // K = 8.64 N·m/rad
  EXPECT_EQ(RobotRefusal(j),
            "test.json: field 'springs.rate_N_per_m' gives K = 2·k·r_j² = 8.64 N·m/rad, "
            "outside the plausible [0.063, 6.3] N·m/rad");
  j = RobotJson();
  j["joint_encoder"]["counts_per_rev"] = 4096;
  EXPECT_NE(RobotRefusal(j).find("14-bit absolute joint encoder"), std::string::npos);
  j = RobotJson();
  j["joint_encoder"]["zero_count"] = 16384;
  EXPECT_EQ(RobotRefusal(j),
            "test.json: field 'joint_encoder.zero_count' = 16384 is outside [0, 16383]");
  j = RobotJson();
  j["limits"]["flexion_deg"] = 120.0;  // beyond the board's 1.6 rad
  EXPECT_NE(RobotRefusal(j).find(
                "'limits.flexion_deg' = 120 is outside the plausible [0, 91.6732]"),
            std::string::npos);
  j = RobotJson();
  j["limits"]["extension_deg"] = 0.0;
  EXPECT_NE(RobotRefusal(j).find("extension_deg < 0 < flexion_deg"), std::string::npos);
  j = RobotJson();
  j["limits"]["torque_Nm"] = 0.0;
  EXPECT_NE(RobotRefusal(j).find("'limits.torque_Nm' = 0 is outside"), std::string::npos);
}

TEST(RobotDescription, DrivesTheFitAndTheRecord) {
  std::string why;
  const auto robot = ParseRobotDescription(RobotJson().dump(), "test.json", &why);
  ASSERT_TRUE(robot) << why;
  BacklashFitOptions fixed;
  fixed.fit_lag = true;
  UseRobotAlpha(*robot, false, &fixed);
  EXPECT_FALSE(fixed.fit_alpha);
  EXPECT_DOUBLE_EQ(fixed.alpha, 1.25);
  EXPECT_TRUE(fixed.fit_lag);  // only the α fields change
  BacklashFitOptions fitted;
  UseRobotAlpha(*robot, true, &fitted);
  EXPECT_TRUE(fitted.fit_alpha);
  EXPECT_DOUBLE_EQ(fitted.alpha_min, 1.0);
  EXPECT_DOUBLE_EQ(fitted.alpha_max, 1.5);

  protocol::CalibrationRecord record;
  record.backlash.c_right = Angle::FromDouble(0.02);
  UseRobotJoint(*robot, &record);
  EXPECT_EQ(record.sea_stiffness, Stiffness::Quantize(1.152));
  EXPECT_EQ(record.joint_zero_count, 300);
  EXPECT_EQ(record.backlash.c_right, Angle::FromDouble(0.02));  // the fit's, untouched
}

TEST(RobotDescription, JointZeroShiftWrapsTheCountDifference) {
  RobotDescription robot;
  constexpr double kCount = 2.0 * std::numbers::pi / 16384;
  robot.joint_zero_count = 120;
  EXPECT_DOUBLE_EQ(JointZeroShift(0, robot), -120 * kCount);
  EXPECT_DOUBLE_EQ(JointZeroShift(120, robot), 0.0);
  robot.joint_zero_count = 16300;  // 184 counts the short way round
  EXPECT_DOUBLE_EQ(JointZeroShift(100, robot), 184 * kCount);
  robot.joint_zero_count = 100;
  EXPECT_DOUBLE_EQ(JointZeroShift(16300, robot), -184 * kCount);
}

}  // namespace
// The description's limits as the board's joint-limit writes: rounded towards zero
// (never looser than the file), against values computed here in double.
TEST(JointLimits, TheDescriptionsLimitsGoToTheBoardNeverLooser) {
  RobotDescription robot;  // −45°..90°, 1 N·m
  robot.torque_limit_Nm = 0.7;
  const auto settings = JointLimitSettings(robot);
  ASSERT_EQ(settings.size(), 3u);
  EXPECT_EQ(settings[0].info->id, protocol::ParamId::kJointTorqueLimit);
  EXPECT_EQ(settings[0].raw, 11744051);  // floor(0.7 · 2^24 = 11744051.2)
  EXPECT_LE(std::ldexp(settings[0].raw, -24), 0.7);
  EXPECT_EQ(settings[1].info->id, protocol::ParamId::kJointAngleMin);
  EXPECT_EQ(settings[1].raw, -13176794);  // −π/4 · 2^24 = −13176794.6, towards zero
  EXPECT_EQ(settings[2].info->id, protocol::ParamId::kJointAngleMax);
  EXPECT_EQ(settings[2].raw, 26353589);  // π/2 · 2^24 = 26353589.3
}

// A trial's amplitude against the travel the board holds: α·A on either side.
TEST(JointLimits, AnAmplitudeBeyondTheTravelIsNamed) {
  JointTravel travel;
  travel.min_rad = -std::numbers::pi / 4;  // −45°
  travel.max_rad = std::numbers::pi / 6;   // 30°
  travel.alpha = 1.25;
  EXPECT_EQ(TravelViolation(24.0, travel), "");  // ±30°
  EXPECT_EQ(TravelViolation(25.0, travel),
            "25.0° moves the joint ±31.2° (α 1.250), beyond its travel [-45.0°, 30.0°]");
  travel.max_rad = std::numbers::pi / 2;
  EXPECT_EQ(TravelViolation(36.0, travel), "");  // ±45°
  EXPECT_NE(TravelViolation(36.1, travel), "");  // beyond the extension side
}

}  // namespace mjc::host
