// mjc list --hand's check against simulated boards (the firmware's application and CAN
// node on the plant, ticked in lock step by a thread of their own) on an in-process bus:
// the scan mjc list runs (host::ScanBus) hears them, and host::CheckHand names the joints
// present and missing, the board the hand does not have and the one whose build
// differs. The boards' builds and node ids are set here, so what the check reports is
// known without it. Every wait is on the boards' own clocks (ScanBus ends when each
// has shown itself), none on this machine's.
#include <gtest/gtest.h>

#include <atomic>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "mjc/app/joint_config.h"
#include "mjc/host/bus_scan.h"
#include "mjc/host/hand.h"
#include "mjc/plant/params.h"
#include "mjc/sim/link_can_port.h"
#include "mjc/sim/sim_board.h"

namespace {

using namespace mjc;

constexpr std::uint32_t kBuildA = 0x1111aaaa;
constexpr std::uint32_t kBuildB = 0x2222bbbb;

// Simulated boards on one bus, ticked in lock step by one thread for kTicks of their
// time (two seconds: the scan needs 1.1 BoardInfo periods, 110 ms, of each): free-running
// threads would let the first board show itself before the others said a word, as no
// powered bus does. The bus keeps every frame in order for the scan, however far behind
// it reads.
class LockStepBoards {
 public:
  static constexpr int kTicks = 2 * static_cast<int>(protocol::kBoardTickHz);

  LockStepBoards(host::InProcessBus& bus,
                 const std::vector<std::pair<std::uint8_t, std::uint32_t>>& boards) {
    for (const auto& [node, build] : boards) {
      auto b = std::make_unique<Board>();
      b->link = bus.Connect();
      b->port = std::make_unique<sim::LinkCanPort>(b->link.get());
      b->board = std::make_unique<sim::SimBoard>(plant::LoadPlantParams("default"),
                                                 Config(node, build), b->port.get());
      boards_.push_back(std::move(b));
    }
    thread_ = std::thread([this] {
      for (int tick = 0; tick < kTicks && !stop_; ++tick) {
        for (auto& b : boards_) {
          b->board->Tick();
          b->board->Poll();
        }
      }
    });
  }
  ~LockStepBoards() {
    stop_ = true;
    thread_.join();
  }

 private:
  struct Board {
    std::unique_ptr<host::CanLink> link;
    std::unique_ptr<sim::LinkCanPort> port;
    std::unique_ptr<sim::SimBoard> board;
  };
  static app::JointBoardConfig Config(std::uint8_t node, std::uint32_t build) {
    app::JointBoardConfig config{app::DefaultJointConfig(), {}, 0, 1};
    config.can.node = node;
    config.can.identity.build = build;
    config.can.identity.instance = static_cast<std::uint16_t>(0x4a00 + node);
    return config;
  }
  std::vector<std::unique_ptr<Board>> boards_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

// A hand of three joints on nodes 1, 2 and 3, written where its robot paths lead to the
// shipped descriptions.
host::Hand ThreeJointHand() {
  const std::string robots = std::string(MJC_SOURCE_DIR) + "/robots/";
  nlohmann::json joints = nlohmann::json::array();
  const char* names[] = {"index_mcp", "index_pip", "middle_mcp"};
  for (int node = 1; node <= 3; ++node) {
    joints.push_back({{"name", names[node - 1]},
                      {"node", node},
                      {"robot", robots + "maestro-default.json"},
                      {"subject",
                       {{"extension_deg", -30},
                        {"flexion_deg", 80},
                        {"torque_Nm", 0.8},
                        {"energy_per_window_mJ", 500}}}});
  }
  const std::string path = ::testing::TempDir() + "/three-joints.json";
  std::ofstream(path) << nlohmann::json{{"name", "three"}, {"joints", joints}}.dump();
  std::string why;
  auto hand = host::LoadHand(path, &why);
  EXPECT_TRUE(hand) << why;
  return hand.value_or(host::Hand{});
}

TEST(HandOnTheBus, ListNamesPresentMissingExtraAndWrongBuild) {
  const host::Hand hand = ThreeJointHand();
  ASSERT_EQ(hand.joints.size(), 3u);
  auto bus = host::InProcessBus::Create();
  auto host_link = bus->Connect();
  // Nodes 1 and 3 of the hand on build A, node 5 (not the hand's) on build B; node 2
  // absent. Three boards of A and one of B would make A the hand's build with fewer
  // boards too: two of A against one of B is the smallest majority.
  LockStepBoards boards(*bus, {{1, kBuildA}, {3, kBuildA}, {5, kBuildB}});
  host::BusScan scan;
  std::string why;
  ASSERT_EQ(host::ScanBus(*host_link, &scan, std::chrono::seconds(30), nullptr, &why),
            host::ScanEnd::kComplete)
      << why;
  ASSERT_EQ(scan.nodes().size(), 3u);

  const host::HandCheck check = host::CheckHand(hand, scan);
  ASSERT_EQ(check.joints.size(), 3u);
  EXPECT_TRUE(check.joints[0].present);
  EXPECT_FALSE(check.joints[1].present);
  EXPECT_TRUE(check.joints[2].present);
  EXPECT_FALSE(check.joints[0].ambiguous);
  EXPECT_FALSE(check.joints[0].in_bootloader);
  EXPECT_FALSE(check.Complete());
  EXPECT_EQ(check.Missing(), std::vector<std::string>{"index_pip"});
  EXPECT_EQ(check.extra, std::vector<int>{5});
  EXPECT_EQ(check.build, kBuildA);
  EXPECT_EQ(check.wrong_build, std::vector<int>{5});

  const auto lines = host::DescribeHandCheck(hand, check, scan);
  ASSERT_EQ(lines.size(), 6u);
  EXPECT_EQ(lines[0], "index_mcp        node 1  present");
  EXPECT_EQ(lines[1], "index_pip        node 2  missing");
  EXPECT_EQ(lines[2], "middle_mcp       node 3  present");
  EXPECT_EQ(lines[3], "node 5: extra, not a joint of three");
  EXPECT_EQ(lines[4], "node 5: wrong build 2222bbbb, most boards run 1111aaaa");
  EXPECT_EQ(lines[5], "three: incomplete, 2 of 3 joints: missing index_pip");
}

TEST(HandOnTheBus, AHandWhoseBoardsAllAnswerIsComplete) {
  const host::Hand hand = ThreeJointHand();
  auto bus = host::InProcessBus::Create();
  auto host_link = bus->Connect();
  LockStepBoards boards(*bus, {{1, kBuildA}, {2, kBuildA}, {3, kBuildA}});
  host::BusScan scan;
  std::string why;
  ASSERT_EQ(host::ScanBus(*host_link, &scan, std::chrono::seconds(30), nullptr, &why),
            host::ScanEnd::kComplete)
      << why;
  const host::HandCheck check = host::CheckHand(hand, scan);
  EXPECT_TRUE(check.Complete());
  EXPECT_TRUE(check.extra.empty());
  EXPECT_TRUE(check.wrong_build.empty());
  EXPECT_EQ(host::DescribeHandCheck(hand, check, scan).back(),
            "three: complete, 3 of 3 joints");
}

}  // namespace
