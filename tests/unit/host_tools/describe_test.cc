// Every code the protocol can carry has its own name: a fault or an outcome added to
// the protocol without one fails here.
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
  EXPECT_GE(valid, 14);
  EXPECT_EQ(host::DescribeFault(Fault::kCanBusOff), "303 (CAN bus-off)");
  EXPECT_EQ(host::DescribeFault(static_cast<Fault>(999)), "999 (unknown fault)");
}

TEST(Describe, EveryCommandOutcomeHasItsOwnName) {
  std::set<std::string_view> names;
  for (unsigned code = 0; code <= 0xFF; ++code) {
    const auto outcome = static_cast<protocol::CommandOutcomeCode>(code);
    if (!protocol::ValidEnumValue(outcome)) {
      EXPECT_EQ(host::OutcomeName(outcome), "unknown outcome") << code;
      continue;
    }
    EXPECT_NE(host::OutcomeName(outcome), "unknown outcome") << code;
    EXPECT_TRUE(names.insert(host::OutcomeName(outcome)).second) << code;
  }
}

}  // namespace
