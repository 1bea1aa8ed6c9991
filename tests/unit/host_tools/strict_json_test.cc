// The loaders' shared policy: unknown keys named with their nearest known key; the
// command line's "did you mean".
#include "mjc/strict_json.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <string_view>

namespace {

using namespace mjc::strict;

TEST(EditDistance, CountsInsertionsDeletionsSubstitutionsAndTranspositions) {
  EXPECT_EQ(EditDistance("", ""), 0u);
  EXPECT_EQ(EditDistance("abc", ""), 3u);
  EXPECT_EQ(EditDistance("", "abc"), 3u);
  EXPECT_EQ(EditDistance("calbrate", "calibrate"), 1u);       // an insertion
  EXPECT_EQ(EditDistance("c_rigth_deg", "c_right_deg"), 1u);  // a transposition
  EXPECT_EQ(EditDistance("kitten", "sitting"), 3u);
  EXPECT_EQ(EditDistance("trial", "trail"), 1u);
}

TEST(Closest, SuggestsOnlyWhatIsNearEnoughToBeASlip) {
  constexpr std::string_view kCommands[] = {"sim",   "log",    "cal",     "calibrate",
                                            "trial", "report", "monitor", "list"};
  EXPECT_EQ(Closest("calbrate", kCommands), "calibrate");
  EXPECT_EQ(Closest("trail", kCommands), "trial");
  EXPECT_EQ(Closest("lst", kCommands), "list");
  EXPECT_EQ(Closest("monitro", kCommands), "monitor");
  EXPECT_FALSE(Closest("flash", kCommands));  // nothing like it
  EXPECT_FALSE(Closest("xyz", kCommands));
  EXPECT_FALSE(Closest("x", {}));
}

TEST(UnknownKey, NamesTheFirstUnknownKeyAndItsNearestKnownOne) {
  constexpr std::string_view kKnown[] = {"iface", "node"};
  EXPECT_FALSE(UnknownKey(nlohmann::json{{"iface", "can0"}, {"node", 2}}, kKnown));
  EXPECT_EQ(UnknownKey(nlohmann::json{{"ifcae", "can0"}}, kKnown),
            "unknown key 'ifcae' (did you mean 'iface'?)");
  EXPECT_EQ(UnknownKey(nlohmann::ordered_json{{"bitrate", 1}}, kKnown),
            "unknown key 'bitrate' (known: iface, node)");
  EXPECT_EQ(UnknownKey(nlohmann::json{{"nod", 1}}, kKnown, "defaults."),
            "unknown key 'defaults.nod' (did you mean 'defaults.node'?)");
  EXPECT_FALSE(UnknownKey(nlohmann::json::array(), kKnown));
}

}  // namespace
