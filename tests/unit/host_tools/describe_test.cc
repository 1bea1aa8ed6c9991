// Every code the protocol can carry has its own name: a fault, an outcome or a parameter
// status added to the protocol without one fails here.
#include "mjc/host/describe.h"

#include <gtest/gtest.h>

#include <set>
#include <string>

namespace {

using namespace mjc;

TEST(Describe, EveryFaultTheProtocolCarriesHasItsOwnName) {
  std::set<std::string_view> names;
  int valid = 0;
  for (unsigned code = 0; code <= 0xFFFF; ++code) {
    const auto fault = static_cast<Fault>(code);
    if (!ValidEnumValue(fault)) {
      EXPECT_EQ(host::FaultName(fault), "unknown fault") << code;
      continue;
    }
    ++valid;
    EXPECT_NE(host::FaultName(fault), "unknown fault") << code;
    EXPECT_TRUE(names.insert(host::FaultName(fault)).second) << "shared name: " << code;
  }
  EXPECT_GE(valid, 15);
  EXPECT_EQ(host::DescribeFault(Fault::kCanBusOff), "303 (CAN bus-off)");
  EXPECT_EQ(host::DescribeFault(Fault::kEmergencyStop), "305 (emergency stop)");
  EXPECT_EQ(host::DescribeFault(static_cast<Fault>(999)), "999 (unknown fault)");
}

// Every value of a one-byte code the protocol accepts has a name of its own, and every
// other reads `unknown`; returns how many were named.
template <class Code, class Name>
std::size_t ExpectOwnNames(Name name, std::string_view unknown) {
  std::set<std::string_view> names;
  for (unsigned code = 0; code <= 0xFF; ++code) {
    const auto value = static_cast<Code>(code);
    if (!protocol::ValidEnumValue(value)) {
      EXPECT_EQ(name(value), unknown) << code;
      continue;
    }
    EXPECT_NE(name(value), unknown) << code;
    EXPECT_TRUE(names.insert(name(value)).second) << code;
  }
  return names.size();
}

TEST(Describe, EveryCommandOutcomeHasItsOwnName) {
  EXPECT_EQ(
      ExpectOwnNames<protocol::CommandOutcomeCode>(host::OutcomeName, "unknown outcome"),
      6u);
}

TEST(Describe, EveryParamStatusHasItsOwnName) {
  EXPECT_EQ(
      ExpectOwnNames<protocol::ParamStatus>(host::ParamStatusName, "unknown status"), 9u);
}

TEST(Describe, EveryCalibrationRefusalSaysWhichField) {
  using protocol::CalibrationResult;
  // Every result a board sends (0..9) has its own text.
  std::set<std::string> texts;
  for (unsigned code = 0; code <= 9; ++code) {
    const std::string text =
        host::DescribeCalibrationResult(static_cast<CalibrationResult>(code), 0);
    EXPECT_EQ(text.find("unknown"), std::string::npos) << code;
    EXPECT_TRUE(texts.insert(text).second) << code;
  }
  // Every field Validate(Calibration) can refuse is named, none as the generic text.
  const mjc::Calibration good;
  std::set<CalibrationError> seen;
  const auto named = [&](const mjc::Calibration& c) {
    const CalibrationError e = Validate(c);
    seen.insert(e);
    return host::DescribeCalibrationResult(CalibrationResult::kOutOfRange,
                                           static_cast<std::uint8_t>(e));
  };
  mjc::Calibration c = good;
  c.backlash.alpha = Scale::FromDouble(0.1);  // below 1/8
  EXPECT_EQ(named(c), "alpha outside (1/8, 8)");
  c = good;
  c.backlash.c_right = Angle::FromDouble(0.6);
  EXPECT_EQ(named(c), "an offset outside ±28.6° (0.5 rad)");
  c = good;
  c.backlash.c_left = Angle::FromDouble(0.1);
  c.backlash.c_right = Angle::FromDouble(0.05);
  EXPECT_EQ(named(c), "c_left above c_right");
  c = good;
  c.sea_stiffness = Stiffness{};
  EXPECT_EQ(named(c), "SEA stiffness outside (0, 100] N·m/rad");
  c = good;
  c.joint_zero_count = 16384;
  EXPECT_EQ(named(c), "joint zero count outside 0..16383");
  EXPECT_EQ(seen.size(), 5u);  // five distinct refusals
  EXPECT_EQ(Validate(good), CalibrationError::kOk);
}

// mjc list's warnings from a bootloader's ChipInfo. FLASH_OPTR's factory value
// 0xFFEFF8AA has nSWBOOT0 (bit 26) = 1: BOOT0 comes from the PB8 pin (RM0440
// FLASH_OPTR; CMSIS FLASH_OPTR_nSWBOOT0_Pos 26). 0xFBEFF8AA is the same with nSWBOOT0
// cleared, as commissioning leaves it.
TEST(Describe, ChipWarningsForTheBootPinAndTheClock) {
  protocol::ChipInfo chip;
  chip.option_bytes = 0xFFEFF8AAu;
  chip.clock = protocol::ClockSource::kHsePll;
  auto w = host::ChipWarnings(chip);
  ASSERT_EQ(w.size(), 1u);
  EXPECT_NE(w[0].find("BOOT0 pin"), std::string::npos) << w[0];
  chip.option_bytes = 0xFBEFF8AAu;
  EXPECT_TRUE(host::ChipWarnings(chip).empty());
  chip.clock = protocol::ClockSource::kHsiPll;
  chip.clock_fault = protocol::ClockFault::kHseTimeout;
  w = host::ChipWarnings(chip);
  ASSERT_EQ(w.size(), 1u);
  EXPECT_NE(w[0].find("HSI16 PLL"), std::string::npos) << w[0];
  EXPECT_NE(w[0].find("does not run"), std::string::npos) << w[0];
  chip.hse_ready = true;
  EXPECT_NE(host::ChipWarnings(chip)[0].find("started late"), std::string::npos);
  EXPECT_EQ(host::StayReasonName(protocol::StayReason::kNoClock), "no crystal clock");
}

}  // namespace
