// mjc list's scan against scripted frames: every node heard, each complete once its
// clock has run a BoardInfo period and a tenth, two boards behind one id told apart.
#include "mjc/host/bus_scan.h"

#include <gtest/gtest.h>

#include "mjc/host/describe.h"
#include "mjc/protocol/codec.h"

namespace {

using namespace mjc;
using namespace mjc::host;

protocol::CanFrame Info(std::uint8_t node, std::uint16_t instance) {
  protocol::BoardInfo info;
  info.build = 0x1958ba84;
  info.reset_cause = protocol::ResetCause::kPowerOn;
  info.instance = instance;
  return protocol::Encode(info, node);
}

protocol::CanFrame Beat(std::uint8_t node, std::uint32_t tick, bool calibrated = false) {
  protocol::Heartbeat h;
  h.tick = tick;
  h.calibrated = calibrated;
  return protocol::Encode(h, node);
}

TEST(BusScan, CompleteOnceEveryNodeHeardRanABoardInfoPeriodOfItsOwnTime) {
  BusScan scan;
  EXPECT_FALSE(scan.Complete());  // nothing heard yet
  scan.Handle(Info(1, 0x3f2a));
  scan.Handle(Beat(1, 50000, true));
  scan.Handle(Beat(2, 7000));
  scan.Handle(protocol::Encode(protocol::HostHeartbeat{1, 7}, 3));  // a host's: no node
  // A BoardInfo period in ticks, heard in tenths of it.
  const auto period = static_cast<std::uint32_t>(kBoardInfoPeriod.count()) *
                      protocol::kBoardTickHz / 1000;
  for (std::uint32_t t = period / 10; t <= period; t += period / 10) {
    scan.Handle(Beat(1, 50000 + t, true));
    scan.Handle(Beat(2, 7000 + t));
  }
  EXPECT_FALSE(scan.Complete());  // one period of their time: another may not have spoken
  scan.Handle(Beat(1, 50000 + period + period / 5, true));
  EXPECT_FALSE(scan.Complete());
  scan.Handle(Info(2, 0x9b01));
  scan.Handle(Beat(2, 7000 + period + period / 5));
  EXPECT_TRUE(scan.Complete());
  ASSERT_EQ(scan.nodes().size(), 2u);
  const ScannedNode& one = scan.nodes().at(1);
  EXPECT_FALSE(one.identity.ambiguous());
  ASSERT_TRUE(one.identity.info());
  EXPECT_EQ(one.identity.info()->instance, 0x3f2a);
  EXPECT_TRUE(one.heartbeat->calibrated);
  EXPECT_EQ(scan.nodes().count(3), 0u);
}

TEST(BusScan, AnExpectedNodeGetsASecondOfTheOthersTimeToSpeak) {
  // A hand of nodes 1 and 2; node 1 shows itself at once, node 2 is slow to speak (a
  // starved process on a loaded machine) or absent. The scan waits for it a second of
  // node 1's own time, however long that takes on the wall.
  BusScan scan;
  scan.Expect({1, 2});
  const std::uint32_t second = protocol::kBoardTickHz;
  scan.Handle(Info(1, 0x3f2a));
  std::uint32_t t = 0;
  for (; t < second / 2; t += second / 10) scan.Handle(Beat(1, 40000 + t));
  ASSERT_TRUE(scan.nodes().at(1).shown);
  EXPECT_FALSE(scan.Complete());  // without Expect, this is where the scan ended
  scan.Handle(Info(2, 0x9b01));   // node 2 speaks at last
  for (std::uint32_t u = 0; u <= second / 5; u += second / 10) {
    scan.Handle(Beat(2, 7000 + u));
  }
  EXPECT_TRUE(scan.Complete());

  BusScan absent;
  absent.Expect({1, 2});
  absent.Handle(Info(1, 0x3f2a));
  for (t = 0; t < second; t += second / 10) {
    absent.Handle(Beat(1, 40000 + t));
    EXPECT_FALSE(absent.Complete()) << t;
  }
  absent.Handle(Beat(1, 40000 + second));
  EXPECT_TRUE(absent.Complete());  // a second of node 1's time: node 2 is missing
  EXPECT_EQ(absent.nodes().count(2), 0u);
}

TEST(BusScan, TwoBoardsWithOneIdAreReported) {
  // Each sends its BoardInfo every period (1000 ticks): the second's first is a sign,
  // both heard twice the proof.
  BusScan scan;
  for (std::uint32_t t = 0; t < 5000; t += 1000) {
    scan.Handle(Info(3, 0x1111));
    scan.Handle(Beat(3, 90000 + t));
    if (t >= 2000) scan.Handle(Info(3, 0x2222));
    scan.Handle(Beat(3, 90010 + t));
  }
  ASSERT_EQ(scan.nodes().count(3), 1u);
  EXPECT_TRUE(scan.nodes().at(3).identity.ambiguous());
  EXPECT_TRUE(scan.nodes().at(3).identity.proven());
  EXPECT_EQ(scan.nodes().at(3).identity.Message(3),
            "node 3 is answered by two boards (instances 1111 and 2222): give each its "
            "own node id");
  EXPECT_TRUE(scan.Complete());  // nothing more to learn
}

TEST(BusScan, OneStrayBoardInfoIsJudgedBeforeTheScanEnds) {
  // One frame of another instance amid a board's own (a flooded bus): the scan goes on
  // until five more BoardInfo frames have come without a second one from it, then
  // reports a sign, not two boards.
  BusScan scan;
  std::uint32_t t = 0;
  const auto period = [&] {
    scan.Handle(Info(3, 0x1111));
    scan.Handle(Beat(3, 90000 + t));
    t += 1000;
  };
  for (int i = 0; i < 3; ++i) period();
  EXPECT_TRUE(scan.Complete());
  scan.Handle(Info(3, 0x5a5a));
  scan.Handle(Beat(3, 90000 + t));
  for (int i = 0; i < 4; ++i) {
    EXPECT_FALSE(scan.Complete()) << "after " << i << " more periods";
    period();
  }
  period();
  EXPECT_TRUE(scan.Complete());
  const BoardIdentity& identity = scan.nodes().at(3).identity;
  EXPECT_TRUE(identity.ambiguous());
  EXPECT_FALSE(identity.proven());
  EXPECT_EQ(identity.Message(3),
            "node 3 showed a sign of a second board on its node id (a BoardInfo of "
            "instance 5a5a amid 1111's): seen once, which a stray or corrupted frame can "
            "also cause (mjc list shows every board on the bus)");
}

TEST(BusScan, TwoBoardsToldApartDoNotEndTheScanBeforeTheOtherNodesSpoke) {
  // Node 2's boards, one 30 s into its time and one just started, are told apart at
  // their first frames.
  BusScan scan;
  scan.Handle(Info(2, 0x1111));
  scan.Handle(Beat(2, 300000));
  scan.Handle(Info(2, 0x2222));
  scan.Handle(Beat(2, 100));
  scan.Handle(Info(2, 0x1111));
  scan.Handle(Beat(2, 301000));
  ASSERT_TRUE(scan.nodes().at(2).identity.ambiguous());
  EXPECT_FALSE(scan.Complete());  // node 1's board may not have spoken yet
  // It speaks late (a board stalled for a moment): heard, and shown by its own clock.
  scan.Handle(Info(1, 0x3f2a));
  for (std::uint32_t t = 0; t <= 1200; t += 100) scan.Handle(Beat(1, 5000 + t));
  EXPECT_FALSE(scan.Complete());  // node 2's boards: two BoardInfo and one so far
  scan.Handle(Info(2, 0x2222));
  scan.Handle(Beat(2, 1100));
  scan.Handle(Info(2, 0x1111));  // two periods of its time: every board has spoken
  EXPECT_TRUE(scan.Complete());
  EXPECT_EQ(scan.nodes().size(), 2u);
}

TEST(BusScan, ABoardWithoutHeartbeatsIsShownByItsBoardInfo) {
  // A bootloader, say: BoardInfo alone, once a second of its time.
  BusScan scan;
  scan.Handle(Info(4, 0x4444));
  scan.Handle(Info(4, 0x4444));
  EXPECT_FALSE(scan.Complete());
  scan.Handle(Info(4, 0x4444));
  EXPECT_TRUE(scan.Complete());
  EXPECT_FALSE(scan.nodes().at(4).heartbeat);
}

protocol::CanFrame Status(std::uint8_t node, std::uint32_t tick_ms) {
  protocol::BootStatus s;
  s.state = protocol::BootState::kReady;
  s.reason = protocol::StayReason::kNoValidImage;
  s.error = protocol::BootError::kImageCrc;
  s.tick_ms = tick_ms;
  return protocol::Encode(s, node);
}

TEST(BusScan, ABootloaderIsShownAfterASecondAndATenthOfItsClock) {
  // It sends its BoardInfo once a second, its BootStatus (with its clock) ten times.
  // Heard first between two of its BoardInfo frames.
  BusScan scan;
  for (std::uint32_t ms = 0; ms <= 500; ms += 100) scan.Handle(Status(5, 300 + ms));
  EXPECT_FALSE(scan.Complete());
  protocol::BoardInfo info;
  info.image = protocol::ImageKind::kBootloader;
  info.build = 0xb0071234;
  info.instance = 0x5151;
  scan.Handle(protocol::Encode(info, 5));
  for (std::uint32_t ms = 600; ms <= 1000; ms += 100) scan.Handle(Status(5, 300 + ms));
  EXPECT_FALSE(scan.Complete());  // a second: a second board may not have spoken yet
  scan.Handle(Status(5, 300 + 1100));
  EXPECT_TRUE(scan.Complete());
  const ScannedNode& n = scan.nodes().at(5);
  EXPECT_TRUE(n.in_bootloader());
  ASSERT_TRUE(n.boot_status);
  EXPECT_EQ(n.boot_status->error, protocol::BootError::kImageCrc);
  EXPECT_EQ(DescribeBootStatus(*n.boot_status), "ready (no valid image: image_crc)");
}

TEST(BusScan, TwoBootloadersWithOneIdAreReported) {
  BusScan scan;
  protocol::BoardInfo info;
  info.image = protocol::ImageKind::kBootloader;
  info.instance = 0x1111;
  scan.Handle(protocol::Encode(info, 6));
  info.instance = 0x2222;
  // Told apart at once, yet the node shows itself like any other (30 BootStatus frames
  // here: their clocks interleave), so the scan goes on while other nodes may speak.
  for (std::uint32_t ms = 0; ms < 1500; ms += 100) {
    scan.Handle(Status(6, 5000 + ms));
    scan.Handle(Status(6, 40 + ms));  // the other's clock, started later
    if (ms == 300) {
      scan.Handle(protocol::Encode(info, 6));
      EXPECT_TRUE(scan.nodes().at(6).identity.ambiguous());
      EXPECT_FALSE(scan.Complete());
    }
  }
  EXPECT_TRUE(scan.nodes().at(6).identity.ambiguous());
  EXPECT_TRUE(scan.Complete());
}

}  // namespace
