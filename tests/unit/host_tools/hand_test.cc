// Hand files (mjc/host/hand.h): the shipped hand loads with its eight joints and their
// descriptions, and every refusal is one line naming the file, the joint and the reason:
// malformed JSON, unknown keys at each level, wrong types, names and node ids out of
// range or given twice, a description that does not load, subject limits looser than
// the description's. CheckHand against scripted scans: present, missing, extra, two
// boards on one id, a bootloader, a build that differs from the others'.
#include "mjc/host/hand.h"

#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "mjc/protocol/codec.h"

namespace mjc::host {
namespace {

const std::string kSource = MJC_SOURCE_DIR;

// A two-joint hand on the shipped descriptions (-45..90° and -45..75°, 1 N·m each).
nlohmann::json TwoJointHand() {
  return nlohmann::json::parse(R"({
    "name": "test-hand",
    "iface": "can1",
    "joints": [
      {"name": "index_mcp", "node": 1, "robot": "maestro-default.json",
       "subject": {"extension_deg": -30, "flexion_deg": 80, "torque_Nm": 0.8,
                   "energy_per_window_mJ": 500}},
      {"name": "index_pip", "node": 2, "robot": "example-alpha-1.25.json",
       "subject": {"extension_deg": -10, "flexion_deg": 75, "torque_Nm": 1.0,
                   "energy_per_window_mJ": 400}}
    ]
  })");
}

// The refusal of `j` (expected: exactly one line), "" when it loads.
std::string HandRefusal(const nlohmann::json& j) {
  std::string why;
  const auto hand = ParseHand(j.dump(), "hands/h.json", kSource + "/robots", &why);
  if (hand) return "";
  EXPECT_EQ(why.find('\n'), std::string::npos) << why;
  return why;
}

#define EXPECT_HAND_REFUSED(json, ...)                        \
  do {                                                        \
    const std::string why_ = HandRefusal(json);               \
    EXPECT_FALSE(why_.empty()) << "loaded";                   \
    EXPECT_EQ(why_.rfind("hands/h.json: ", 0), 0u) << why_;   \
    for (const char* part_ : {__VA_ARGS__}) {                 \
      EXPECT_NE(why_.find(part_), std::string::npos) << why_; \
    }                                                         \
  } while (false)

TEST(Hand, TheShippedHandLoadsWithEightJointsOnEightNodes) {
  std::string why;
  const auto hand = LoadHand(kSource + "/hands/maestro-right.json", &why);
  ASSERT_TRUE(hand) << why;
  EXPECT_EQ(hand->name, "maestro-right");
  EXPECT_EQ(hand->iface, "can0");
  ASSERT_EQ(hand->joints.size(), 8u);
  for (int node = 1; node <= 8; ++node) {
    const HandJoint* j = hand->AtNode(node);
    ASSERT_NE(j, nullptr) << node;
    EXPECT_EQ(hand->Find(j->name), j);
    // Each description as the robot loader reads the same file on its own.
    const auto d = LoadRobotDescription(j->robot_path, &why);
    ASSERT_TRUE(d) << why;
    EXPECT_EQ(j->description.name, d->name);
    EXPECT_GE(j->subject.extension_deg, d->extension_limit_deg) << j->name;
    EXPECT_LE(j->subject.flexion_deg, d->flexion_limit_deg) << j->name;
    EXPECT_LE(j->subject.torque_Nm, d->torque_limit_Nm) << j->name;
  }
  EXPECT_EQ(hand->Find("index_mcp")->node, 4);
  EXPECT_EQ(hand->Find("index_mcp")->description.name, "example-alpha-1.25");
  EXPECT_EQ(hand->Find("nothing"), nullptr);
  EXPECT_EQ(hand->JointNames(),
            "thumb_cmc, thumb_mcp, thumb_ip, index_mcp, index_pip, middle_mcp, "
            "middle_pip, ring_little_mcp");
}

TEST(Hand, AHandReadsEveryField) {
  std::string why;
  const auto hand = ParseHand(TwoJointHand().dump(), "h.json", kSource + "/robots", &why);
  ASSERT_TRUE(hand) << why;
  EXPECT_EQ(hand->iface, "can1");
  const HandJoint& pip = hand->joints[1];
  EXPECT_EQ(pip.name, "index_pip");
  EXPECT_EQ(pip.node, 2);
  EXPECT_EQ(pip.robot, "example-alpha-1.25.json");
  EXPECT_EQ(pip.robot_path, kSource + "/robots/example-alpha-1.25.json");
  EXPECT_EQ(pip.description.flexion_limit_deg, 75.0);
  EXPECT_EQ(pip.subject.extension_deg, -10.0);
  EXPECT_EQ(pip.subject.flexion_deg, 75.0);  // the description's own limit: allowed
  EXPECT_EQ(pip.subject.torque_Nm, 1.0);
  EXPECT_EQ(pip.subject.energy_per_window_mJ, 400.0);
  auto no_iface = TwoJointHand();
  no_iface.erase("iface");
  const auto bare = ParseHand(no_iface.dump(), "h.json", kSource + "/robots", &why);
  ASSERT_TRUE(bare) << why;
  EXPECT_FALSE(bare->iface);
}

TEST(Hand, MalformedFilesAreRefused) {
  std::string why;
  EXPECT_FALSE(ParseHand("{\"name\": ", "hands/h.json", ".", &why));
  EXPECT_NE(why.find("hands/h.json: not valid JSON"), std::string::npos) << why;
  EXPECT_FALSE(ParseHand(R"({"name": "a", "name": "b", "joints": []})", "hands/h.json",
                         ".", &why));
  EXPECT_NE(why.find("key 'name' appears twice"), std::string::npos) << why;
  EXPECT_FALSE(LoadHand("/nonexistent/hand.json", &why));
  EXPECT_NE(why.find("/nonexistent/hand.json: cannot open"), std::string::npos) << why;
}

TEST(Hand, UnknownKeysAreRefusedAtEveryLevel) {
  auto j = TwoJointHand();
  j["jionts"] = 1;
  EXPECT_HAND_REFUSED(j, "unknown key 'jionts'", "did you mean 'joints'");
  j = TwoJointHand();
  j["joints"][1]["nod"] = 2;
  EXPECT_HAND_REFUSED(j, "joints[1]", "unknown key 'nod'", "'node'");
  j = TwoJointHand();
  j["joints"][0]["subject"]["torque_nm"] = 1;
  EXPECT_HAND_REFUSED(j, "joint 'index_mcp'", "unknown key 'subject.torque_nm'",
                      "'subject.torque_Nm'");
}

TEST(Hand, WrongTypesAndMissingFieldsAreRefused) {
  auto j = TwoJointHand();
  j["name"] = 3;
  EXPECT_HAND_REFUSED(j, "field 'name' must be a string");
  j = TwoJointHand();
  j["joints"] = nlohmann::json::object();
  EXPECT_HAND_REFUSED(j, "field 'joints' must be an array");
  j = TwoJointHand();
  j["joints"] = nlohmann::json::array();
  EXPECT_HAND_REFUSED(j, "holds 0 joints");
  j = TwoJointHand();
  j["joints"][0] = 1;
  EXPECT_HAND_REFUSED(j, "joints[0] must be an object");
  j = TwoJointHand();
  j["joints"][1]["node"] = "2";
  EXPECT_HAND_REFUSED(j, "joint 'index_pip'", "field 'node' must be an integer");
  j = TwoJointHand();
  j["joints"][1]["robot"] = nullptr;
  EXPECT_HAND_REFUSED(j, "joint 'index_pip'", "field 'robot' must be a string");
  j = TwoJointHand();
  j["joints"][1]["subject"] = 5;
  EXPECT_HAND_REFUSED(j, "joint 'index_pip'", "field 'subject' must be an object");
  j = TwoJointHand();
  j["joints"][1]["subject"].erase("energy_per_window_mJ");
  EXPECT_HAND_REFUSED(j, "joint 'index_pip'",
                      "'subject.energy_per_window_mJ' is missing");
  j = TwoJointHand();
  j["joints"][0]["subject"]["flexion_deg"] = "80";
  EXPECT_HAND_REFUSED(j, "joint 'index_mcp'", "'subject.flexion_deg' must be a number");
}

TEST(Hand, NamesAndNodeIdsOutOfRangeAreRefused) {
  auto j = TwoJointHand();
  j["name"] = "a hand";
  EXPECT_HAND_REFUSED(j, "field 'name'", "[A-Za-z0-9_.-]");
  j = TwoJointHand();
  j["iface"] = "a-much-too-long-name";
  EXPECT_HAND_REFUSED(j, "field 'iface'", "not an interface name");
  j = TwoJointHand();
  j["joints"][0]["name"] = "Index MCP";
  EXPECT_HAND_REFUSED(j, "joints[0]", "field 'name'", "[a-z0-9_]");
  for (const int node : {0, 9, -1}) {
    j = TwoJointHand();
    j["joints"][1]["node"] = node;
    EXPECT_HAND_REFUSED(j, "joint 'index_pip'", "field 'node'", "outside [1, 8]");
  }
  j = TwoJointHand();
  auto joint = j["joints"][0];
  for (int i = 0; i < 8; ++i) {
    joint["name"] = "j" + std::to_string(i);
    j["joints"].push_back(joint);
  }
  EXPECT_HAND_REFUSED(j, "holds 10 joints", "1 to 8");
}

TEST(Hand, ANodeIdOrANameGivenTwiceIsRefused) {
  auto j = TwoJointHand();
  j["joints"][1]["node"] = 1;
  EXPECT_HAND_REFUSED(j, "joint 'index_pip'", "node 1 is joint 'index_mcp' already");
  j = TwoJointHand();
  j["joints"][1]["name"] = "index_mcp";
  j["joints"][1]["node"] = 3;
  EXPECT_HAND_REFUSED(j, "joint 'index_mcp'", "given to two joints");
}

TEST(Hand, ADescriptionThatDoesNotLoadIsRefusedWithItsReason) {
  auto j = TwoJointHand();
  j["joints"][1]["robot"] = "no-such-joint.json";
  EXPECT_HAND_REFUSED(j, "joint 'index_pip'", "robot description refused",
                      "no-such-joint.json: cannot open");
  // A description the robot loader refuses: its own reason is quoted.
  const std::string dir = ::testing::TempDir();
  auto robot =
      nlohmann::json::parse(std::ifstream(kSource + "/robots/maestro-default.json"));
  robot["springs"]["rate_N_per_m"] = 5.0;
  std::ofstream(dir + "/bad-robot.json") << robot.dump();
  j = TwoJointHand();
  j["joints"][0]["robot"] = dir + "/bad-robot.json";
  EXPECT_HAND_REFUSED(j, "joint 'index_mcp'", "robot description refused",
                      "field 'springs.rate_N_per_m'");
  j = TwoJointHand();
  j["joints"][0]["robot"] = "";
  EXPECT_HAND_REFUSED(j, "joint 'index_mcp'", "field 'robot' is empty");
}

TEST(Hand, SubjectLimitsLooserThanTheDescriptionAreRefused) {
  // index_pip's description (example-alpha-1.25): -45..75°, 1 N·m.
  auto j = TwoJointHand();
  j["joints"][1]["subject"]["extension_deg"] = -45.5;
  EXPECT_HAND_REFUSED(j, "joint 'index_pip'", "subject.extension_deg", "-45.5",
                      "extension limit -45°", "example-alpha-1.25");
  j = TwoJointHand();
  j["joints"][1]["subject"]["flexion_deg"] = 75.1;
  EXPECT_HAND_REFUSED(j, "joint 'index_pip'", "subject.flexion_deg", "flexion limit 75°");
  j = TwoJointHand();
  j["joints"][1]["subject"]["torque_Nm"] = 1.01;
  EXPECT_HAND_REFUSED(j, "joint 'index_pip'", "subject.torque_Nm", "torque limit 1 N·m");
  // Not limits at all: the wrong sign, zero.
  j = TwoJointHand();
  j["joints"][1]["subject"]["extension_deg"] = 5;
  EXPECT_HAND_REFUSED(j, "joint 'index_pip'", "subject.extension_deg", "below 0");
  j = TwoJointHand();
  j["joints"][1]["subject"]["flexion_deg"] = -5;
  EXPECT_HAND_REFUSED(j, "joint 'index_pip'", "subject.flexion_deg", "above 0");
  j = TwoJointHand();
  j["joints"][1]["subject"]["torque_Nm"] = 0;
  EXPECT_HAND_REFUSED(j, "joint 'index_pip'", "subject.torque_Nm", "above 0");
  j = TwoJointHand();
  j["joints"][1]["subject"]["energy_per_window_mJ"] = 0;
  EXPECT_HAND_REFUSED(j, "joint 'index_pip'", "subject.energy_per_window_mJ", "above 0");
  // A window carries at most torque × range: 1 N·m over 85° = 1483.5 mJ.
  j = TwoJointHand();
  j["joints"][1]["subject"]["energy_per_window_mJ"] = 1484;
  EXPECT_HAND_REFUSED(j, "joint 'index_pip'", "subject.energy_per_window_mJ",
                      "more than a window can carry", "1483.53 mJ");
  j["joints"][1]["subject"]["energy_per_window_mJ"] = 1483;
  EXPECT_EQ(HandRefusal(j), "");
}

protocol::CanFrame HandInfo(std::uint8_t node, std::uint32_t build,
                            protocol::ImageKind image = protocol::ImageKind::kApplication,
                            std::uint16_t instance = 0x1000) {
  protocol::BoardInfo info;
  info.build = build;
  info.image = image;
  info.instance = static_cast<std::uint16_t>(instance + node);
  return protocol::Encode(info, node);
}

protocol::CanFrame HandBeat(std::uint8_t node, std::uint32_t tick) {
  protocol::Heartbeat h;
  h.tick = tick;
  return protocol::Encode(h, node);
}

TEST(Hand, CheckNamesPresentMissingExtraAndWrongBuild) {
  std::string why;
  const auto hand = LoadHand(kSource + "/hands/maestro-right.json", &why);
  ASSERT_TRUE(hand) << why;
  BusScan scan;
  // Nodes 1-5 and 7 on build a, node 6 on build b, nothing on 8; node 3 in its
  // bootloader (another image: not judged by its build).
  for (const int node : {1, 2, 4, 5, 7})
    scan.Handle(HandInfo(static_cast<std::uint8_t>(node), 0xaaaa0001));
  scan.Handle(HandInfo(6, 0xbbbb0002));
  scan.Handle(HandInfo(3, 0xcccc0003, protocol::ImageKind::kBootloader));
  const HandCheck check = CheckHand(*hand, scan);
  ASSERT_EQ(check.joints.size(), 8u);
  EXPECT_FALSE(check.Complete());
  EXPECT_EQ(check.Missing(), std::vector<std::string>{"ring_little_mcp"});
  EXPECT_TRUE(check.joints[2].in_bootloader);
  EXPECT_FALSE(check.joints[0].in_bootloader);
  EXPECT_EQ(check.build, 0xaaaa0001u);
  EXPECT_EQ(check.wrong_build, std::vector<int>{6});
  EXPECT_TRUE(check.extra.empty());
  scan.Handle(HandInfo(8, 0xaaaa0001));
  EXPECT_TRUE(CheckHand(*hand, scan).Complete());
}

TEST(Hand, CheckNamesBoardsTheHandDoesNotHaveAndTwoBoardsOnOneId) {
  std::string why;
  const auto hand = ParseHand(TwoJointHand().dump(), "h.json", kSource + "/robots", &why);
  ASSERT_TRUE(hand) << why;
  BusScan scan;
  scan.Handle(HandInfo(1, 7));
  scan.Handle(HandInfo(2, 7));
  scan.Handle(HandInfo(5, 7));
  HandCheck check = CheckHand(*hand, scan);
  EXPECT_TRUE(check.Complete());
  EXPECT_EQ(check.extra, std::vector<int>{5});
  EXPECT_TRUE(check.wrong_build.empty());
  // A second board on node 2: another instance, each heard with its own clock.
  for (std::uint32_t t = 0; t < 5000; t += 1000) {
    scan.Handle(HandInfo(2, 7));
    scan.Handle(HandBeat(2, 90000 + t));
    scan.Handle(HandInfo(2, 7, protocol::ImageKind::kApplication, 0x2000));
    scan.Handle(HandBeat(2, 10 + t));
  }
  check = CheckHand(*hand, scan);
  EXPECT_TRUE(check.joints[1].ambiguous);
  EXPECT_FALSE(check.Complete());
  EXPECT_TRUE(check.Missing().empty());
}

}  // namespace
}  // namespace mjc::host
