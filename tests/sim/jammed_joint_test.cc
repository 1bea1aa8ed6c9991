// The calibration sweep on a joint that cannot follow the cable (a hand strapped in
// during the sweep, experiment_rig.h): the record is no play operator's, and the host's
// fit must refuse it rather than upload offsets that would make every later torque
// wrong. The fit's refusals on synthetic records are in
// tests/unit/host_tools/calibration_fit_test.cc; this is the closed loop.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>

#include "experiment_rig.h"

namespace {

using namespace mjc;
using namespace mjc::sim;

constexpr double kDeg = std::numbers::pi / 180.0;

double Span(const std::vector<double>& v) {
  const auto [low, high] = std::minmax_element(v.begin(), v.end());
  return *high - *low;
}

void ExpectRefused(const CalibrationOutcome& cal, const std::string& why) {
  std::printf("[ held     ] motor swings %.1f°, joint %.3f°: %s\n",
              Span(cal.motor_rad) / kDeg, Span(cal.joint_rad) / kDeg,
              cal.fit.message.c_str());
  EXPECT_FALSE(cal.uploaded);
  EXPECT_FALSE(host::ToFirmwareConfig(cal.fit, nullptr).has_value());
  EXPECT_NE(cal.message.find("calibration refused"), std::string::npos) << cal.message;
  EXPECT_NE(cal.fit.message.find(why), std::string::npos) << cal.fit.message;
}

TEST(SimHeldJoint, CalibrationOfAJammedJointIsRefusedAsUnidentifiable) {
  // Setup and exercise: the paper's sweep with the joint jammed.
  const CalibrationOutcome cal = rig::CalibrateHeldJoint(rig::kJammedJointStiffness);

  // Verify: the sweep ran to its end (no board fault), the motor swung ±30° less the
  // slack while the joint stood within a few counts of noise, and the fit was refused:
  // a still joint is best explained by a dead band as wide as the motor's swing.
  ASSERT_FALSE(cal.motor_rad.empty()) << cal.message;
  EXPECT_GT(Span(cal.motor_rad), 50.0 * kDeg);
  EXPECT_LT(Span(cal.joint_rad), 0.2 * kDeg);
  ExpectRefused(cal, "neither c_r nor c_l can be identified");
}

TEST(SimHeldJoint, CalibrationOfAHeldJointIsRefusedForItsResidual) {
  // Setup and exercise: the paper's sweep with the joint held by a soft attachment.
  const CalibrationOutcome cal = rig::CalibrateHeldJoint(rig::kHeldJointStiffness);

  // Verify: the joint moved, but far less than the cable asks (K/(K + k) ≈ 0.56 of the
  // motor's travel beyond the slack), and the fit was refused for its residual.
  ASSERT_FALSE(cal.motor_rad.empty()) << cal.message;
  EXPECT_GT(Span(cal.joint_rad), 5.0 * kDeg);
  EXPECT_LT(Span(cal.joint_rad), 0.75 * Span(cal.motor_rad));
  ExpectRefused(cal, "the residual");
  EXPECT_GT(cal.fit.rms_error_rad, host::BacklashFitOptions{}.max_rms_error_rad);
}

}  // namespace
