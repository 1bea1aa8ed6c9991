// The simulated board from its reset on (sim::BootingBoard): its bootloader decides as
// the chip's does — stays without a valid image, hands over after its 200 ms hold window
// of board time, stays when held or asked, stays after three starts the application
// never confirmed — and the application it hands over to reports the installed image's
// build with image 0, the bootloader its own with image 1, both with the node id of the
// identity record. Observed on the bus, as a host sees it.
#include "mjc/sim/booting_board.h"

#include <gtest/gtest.h>

#include <vector>

#include "flash_rig.h"
#include "mjc/boot/identity_store.h"

namespace {

using namespace mjc;
using test::FlashRig;

constexpr std::uint32_t kBuild = 0x1c37bb4au;

// What the board sent during `ms` of its time (what it sent before is dropped).
std::vector<protocol::CanFrame> Listen(FlashRig& rig, int ms) {
  while (rig.host_link()->Receive(0)) {
  }
  std::vector<protocol::CanFrame> out;
  for (int i = 0; i < ms; ++i) {
    rig.StepMs();
    for (host::ReceiveResult r = rig.host_link()->Receive(0); r;
         r = rig.host_link()->Receive(0)) {
      out.push_back(r->frame);
    }
  }
  return out;
}

template <class M>
std::vector<M> Decoded(const std::vector<protocol::CanFrame>& frames) {
  std::vector<M> out;
  for (const auto& f : frames) {
    M m;
    if (protocol::Decode(f, &m) == protocol::DecodeError::kOk) out.push_back(m);
  }
  return out;
}

void Install(FlashRig& rig, std::uint8_t node) {
  ASSERT_EQ(boot::IdentityStore(&rig.flash(), 252, 253).Save({node, 1}),
            boot::IdentityResult::kOk);
  ASSERT_TRUE(sim::InstallImage(
      rig.flash(), sim::StandInImage(kBuild, true, 1795000000u, "v1-dirty")));
}

TEST(BootingBoard, StaysInItsBootloaderWithoutAValidImage) {
  FlashRig rig(1);
  ASSERT_EQ(boot::IdentityStore(&rig.flash(), 252, 253).Save({4, 1}),
            boot::IdentityResult::kOk);
  rig.PowerOn();
  const auto frames = Listen(rig, 1000);
  EXPECT_FALSE(rig.board()->in_application());
  EXPECT_EQ(rig.board()->node(), 4);  // the identity record's, not the default 1
  const auto infos = Decoded<protocol::BoardInfo>(frames);
  ASSERT_FALSE(infos.empty());
  EXPECT_EQ(infos[0].image, protocol::ImageKind::kBootloader);
  EXPECT_EQ(infos[0].build, FlashRig::kBootloaderBuild);
  EXPECT_EQ(infos[0].reset_cause, protocol::ResetCause::kPowerOn);
  const auto statuses = Decoded<protocol::BootStatus>(frames);
  ASSERT_GE(statuses.size(), 10u);  // every 100 ms of its time
  EXPECT_EQ(statuses.back().state, protocol::BootState::kReady);
  EXPECT_EQ(statuses.back().reason, protocol::StayReason::kNoValidImage);
  EXPECT_EQ(statuses.back().error, protocol::BootError::kNoImage);
  for (const auto& f : frames) EXPECT_EQ(protocol::NodeOf(f.id), 4);
}

TEST(BootingBoard, HandsOverAfterTheHoldWindowAndReportsTheInstalledBuild) {
  FlashRig rig;
  Install(rig, 2);
  rig.PowerOn();
  rig.RunMs(199);
  EXPECT_FALSE(rig.board()->in_application());
  const auto frames = Listen(rig, 300);
  ASSERT_TRUE(rig.board()->in_application());
  const auto infos = Decoded<protocol::BoardInfo>(frames);
  ASSERT_FALSE(infos.empty());
  EXPECT_EQ(infos.back().image, protocol::ImageKind::kApplication);
  EXPECT_EQ(infos.back().build, kBuild);
  EXPECT_TRUE(infos.back().dirty);
  EXPECT_EQ(infos.back().instance, 0x5A5A);  // the bootloader's too: one chip
  EXPECT_FALSE(Decoded<protocol::Heartbeat>(frames).empty());
  EXPECT_EQ(rig.board()->node(), 2);
}

TEST(BootingBoard, AHoldInTheWindowKeepsItAndTheApplicationEntersOnlyAtRest) {
  FlashRig rig;
  Install(rig, 2);
  rig.PowerOn();
  rig.RunMs(100);
  rig.SendFromHost(protocol::Encode(protocol::BootHold{}, 2));
  rig.RunMs(500);
  const boot::Bootloader* held = rig.board()->bootloader();
  ASSERT_TRUE(held != nullptr);
  EXPECT_EQ(held->reason(), protocol::StayReason::kHoldFrame);
  // A Boot starts the image: a software reset, then the window, then the application.
  rig.SendFromHost(
      protocol::Encode(protocol::BootCommand{protocol::BootRequest::kBoot, 1}, 2));
  rig.RunMs(300);
  ASSERT_TRUE(rig.board()->in_application());
  // Asked by a host at rest: into the bootloader, which stays (requested) and says so.
  rig.SendFromHost(protocol::Encode(protocol::BootHold{}, 2));
  const auto frames = Listen(rig, 300);
  const boot::Bootloader* asked = rig.board()->bootloader();
  ASSERT_TRUE(asked != nullptr);
  EXPECT_EQ(asked->reason(), protocol::StayReason::kRequested);
  const auto results = Decoded<protocol::BootResult>(frames);
  ASSERT_FALSE(results.empty());
  EXPECT_EQ(results.front().request, protocol::BootRequest::kHold);
  EXPECT_EQ(results.front().error, protocol::BootError::kNone);
  const auto infos = Decoded<protocol::BoardInfo>(frames);
  ASSERT_FALSE(infos.empty());
  EXPECT_EQ(infos.front().image, protocol::ImageKind::kBootloader);
  EXPECT_EQ(infos.front().reset_cause, protocol::ResetCause::kSoftware);
  // The request lasted one reset: the next one starts the application again.
  rig.board()->PinReset();
  rig.RunMs(300);
  EXPECT_TRUE(rig.board()->in_application());
}

TEST(BootingBoard, ThreeStartsNeverConfirmedKeepItInItsBootloader) {
  FlashRig rig;
  Install(rig, 2);
  rig.PowerOn();
  // Three starts that each end (a watchdog, a crash: a reset keeping RAM) before the
  // application's 2 s of healthy running.
  for (int start = 0; start < 3; ++start) {
    rig.RunMs(1000);
    ASSERT_TRUE(rig.board()->in_application()) << start;
    rig.board()->PinReset();
  }
  rig.RunMs(1000);
  const boot::Bootloader* looped = rig.board()->bootloader();
  ASSERT_TRUE(looped != nullptr);
  EXPECT_EQ(looped->reason(), protocol::StayReason::kBootLoop);
  // A host's Boot gives the image its starts afresh; once it has run 2 s it confirms,
  // and later resets start it again.
  rig.SendFromHost(
      protocol::Encode(protocol::BootCommand{protocol::BootRequest::kBoot, 1}, 2));
  rig.RunMs(2500);
  ASSERT_TRUE(rig.board()->in_application());
  for (int start = 0; start < 4; ++start) {
    rig.board()->PinReset();
    rig.RunMs(2500);
    EXPECT_TRUE(rig.board()->in_application()) << start;
  }
}

}  // namespace
