// mjc flash's update (host::FirmwareUpdate) against a simulated board — its real
// bootloader logic, then its application — on an in-process bus in the board's time
// (flash_rig.h): a running board caught, updated and started with the new build, its
// node id and calibration untouched; a board in a motion refused; a hanging board
// caught by its reset line's pulse; a power cut in the
// middle, the board's bootloader waiting, a second update recovering it; lost frames and
// answers sent again; an image for other hardware refused with the old image started
// again; a silent node. And the image checks that keep a bad file off the bus.
#include "mjc/host/firmware_update.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "flash_rig.h"
#include "image_file.h"
#include "mjc/app/calibration_store.h"
#include "mjc/boot/identity_store.h"
#include "mjc/boot/layout.h"
#include "mjc/gpio/reset_line.h"
#include "mjc/protocol/little_endian.h"

namespace {

using namespace mjc;
using host::UpdateEnd;
using test::FlashRig;

constexpr std::uint8_t kNode = 3;
constexpr std::uint32_t kOldBuild = 0x01d0001du;
constexpr std::uint32_t kNewBuild = 0x5eed1234u;

// A packed image for the joint board: a vector table (SRAM's top, a Thumb reset handler
// inside), then bytes of `seed`.
std::vector<std::uint8_t> PackedImage(
    std::uint32_t commit, std::size_t bytes, std::uint32_t seed, std::uint8_t hw_min = 1,
    std::uint8_t hw_max = 1, std::uint16_t board_type = 1,
    std::uint32_t load_address = boot::kG474Layout.ImageAddress()) {
  std::vector<std::uint8_t> image(bytes);
  std::mt19937 rng(seed);
  for (auto& b : image) b = static_cast<std::uint8_t>(rng());
  protocol::PutLe(&image[0], 0x20018000u, 4);
  protocol::PutLe(&image[4], load_address + 0x201u, 4);
  boot::ImageHeader h;
  h.board_type = board_type;
  h.hardware_min = hw_min;
  h.hardware_max = hw_max;
  h.load_address = load_address;
  h.commit = commit;
  h.commit_time_unix = 1795486377u;
  const std::string d = "test-" + std::to_string(commit);
  std::copy(d.begin(), d.end(), h.describe.begin());
  return boot::PackImage(image, h);
}

host::FirmwareImage Checked(std::vector<std::uint8_t> file) {
  std::string why;
  auto image = host::CheckFirmwareImage(std::move(file), "test.bin", &why);
  EXPECT_TRUE(image) << why;
  return image ? *image : host::FirmwareImage{};
}

protocol::CalibrationRecord Calibration() {
  protocol::CalibrationRecord r;
  r.backlash.c_right = Angle::FromDouble(0.0192);
  r.backlash.c_left = Angle::FromDouble(-0.0157);
  r.sea_stiffness = Stiffness::FromDouble(0.63);
  r.joint_zero_count = 1234;
  return r;
}

// Every page outside the application region (bootloader, bank 2, identity,
// calibration), as bytes.
std::vector<std::uint8_t> Outside(hal::SimFlash& flash) {
  std::vector<std::uint8_t> out;
  std::vector<std::uint8_t> page(hal::Flash::kPageSize);
  const auto& l = boot::kG474Layout;
  for (std::uint32_t p = 0; p < sim::kBoardFlashPages; ++p) {
    if (p >= l.app_first_page && p < l.app_first_page + l.app_pages) continue;
    (void)flash.Read(p, 0, page);
    out.insert(out.end(), page.begin(), page.end());
  }
  return out;
}

// A commissioned board: node 3, an old image, a calibration stored.
void Commission(FlashRig& rig, bool with_image = true) {
  ASSERT_EQ(boot::IdentityStore(&rig.flash(), 252, 253).Save({kNode, 1}),
            boot::IdentityResult::kOk);
  if (with_image) {
    ASSERT_TRUE(sim::InstallImage(
        rig.flash(), sim::StandInImage(kOldBuild, false, 1795000000u, "old")));
  }
  app::CalibrationStore store(&rig.flash(), sim::kCalibrationPageA,
                              sim::kCalibrationPageB);
  ASSERT_EQ(store.Save(Calibration()), app::StoreResult::kOk);
}

// The board runs its application with `build`, node 3, calibrated.
void ExpectRunning(FlashRig& rig, std::uint32_t build) {
  ASSERT_TRUE(rig.board() != nullptr);
  ASSERT_TRUE(rig.board()->in_application());
  EXPECT_EQ(rig.board()->node(), kNode);
  EXPECT_EQ(rig.board()->application()->node().config().identity.build, build);
  rig.RunMs(2);
  EXPECT_TRUE(rig.board()->application()->app().calibrated());
}

TEST(FirmwareUpdate, UpdatesARunningBoardAndKeepsItsNodeIdAndCalibration) {
  FlashRig rig(1);  // without its identity record it would answer as node 1
  Commission(rig);
  rig.PowerOn();
  rig.RunMs(500);  // the hold window, then the application
  ExpectRunning(rig, kOldBuild);
  const std::vector<std::uint8_t> outside = Outside(rig.flash());
  const auto image = Checked(PackedImage(kNewBuild, 64 * 1024, 7));

  std::vector<host::UpdateProgress> progress;
  auto options = rig.Options();
  options.progress = [&](const host::UpdateProgress& p) { progress.push_back(p); };
  const host::UpdateResult r = rig.Update(kNode, image, options);

  EXPECT_EQ(r.end, UpdateEnd::kUpdated) << r.message;
  EXPECT_EQ(r.chunks_resent, 0);
  EXPECT_EQ(r.restarts, 0);
  ExpectRunning(rig, kNewBuild);
  // The image in the region is the file, byte for byte; nothing outside it changed.
  std::vector<std::uint8_t> region(image.file.size());
  ASSERT_EQ(boot::AppRegion(&rig.flash(), boot::kG474Layout).Read(0, region),
            protocol::BootError::kNone);
  EXPECT_TRUE(region == image.file);
  EXPECT_TRUE(Outside(rig.flash()) == outside);
  // Caught, uploaded in order to the end, committed, started.
  ASSERT_GE(progress.size(), 4u);
  EXPECT_EQ(progress.front().phase, host::UpdateProgress::Phase::kCatching);
  EXPECT_EQ(progress.back().phase, host::UpdateProgress::Phase::kBooting);
  std::uint32_t last = 0;
  for (const auto& p : progress) {
    EXPECT_GE(p.programmed, last);
    last = p.programmed;
  }
  EXPECT_EQ(last, image.header.length);
  // The application entered the bootloader (a software reset), the Boot reset again.
  EXPECT_EQ(rig.board()->resets(), 3u);
}

TEST(FirmwareUpdate, ABoardInAMotionIsRefusedAndNothingIsDone) {
  FlashRig rig;
  Commission(rig);
  rig.PowerOn();
  rig.RunMs(500);
  ASSERT_TRUE(rig.board()->in_application());
  protocol::TrialConfig t;
  t.amplitude = Angle::FromDouble(0.1);
  t.repetitions = 5;
  rig.SendFromHost(protocol::Encode(t, kNode));
  rig.SendFromHost(protocol::Encode(protocol::Command{protocol::CommandCode::kStartTrial,
                                                      1, 0, protocol::ConfigDigestOf(t)},
                                    kNode));
  rig.RunMs(20);
  ASSERT_EQ(rig.board()->application()->app().state(), protocol::BoardState::kRunning);
  rig.RunMs(100);
  std::vector<std::uint8_t> region_before(4096);
  boot::AppRegion region(&rig.flash(), boot::kG474Layout);
  ASSERT_EQ(region.Read(0, region_before), protocol::BootError::kNone);

  const host::UpdateResult r =
      rig.Update(kNode, Checked(PackedImage(kNewBuild, 4096, 1)));

  EXPECT_EQ(r.end, UpdateEnd::kMotionRunning) << r.message;
  EXPECT_NE(r.message.find("stop it first (mjc stop --node 3)"), std::string::npos)
      << r.message;
  EXPECT_EQ(rig.host_sent(protocol::Function::kBootIsoTpToBoard), 0u);
  EXPECT_EQ(rig.host_sent(protocol::Function::kBootCommand), 0u);
  ASSERT_TRUE(rig.board()->in_application());
  EXPECT_EQ(rig.board()->application()->app().state(), protocol::BoardState::kRunning);
  EXPECT_EQ(rig.board()->resets(), 1u);
  std::vector<std::uint8_t> region_after(4096);
  ASSERT_EQ(region.Read(0, region_after), protocol::BootError::kNone);
  EXPECT_TRUE(region_after == region_before);
}

// mjc flash --reset-line: the pulse right after the first hold restarts a board whose
// application hangs, and the holds catch its bootloader in the hold window.
TEST(FirmwareUpdate, AResetLineCatchesAHangingBoardInItsBootloader) {
  FlashRig rig;
  Commission(rig);
  rig.PowerOn();
  rig.RunMs(500);
  ASSERT_TRUE(rig.board()->in_application());
  rig.hung = true;  // its main loop and tick stopped: no frame, no answer
  const auto image = Checked(PackedImage(kNewBuild, 8 * 1024, 3));
  // Without a reset line nothing catches it: it talked, then went silent.
  const host::UpdateResult without = rig.Update(kNode, image);
  EXPECT_EQ(without.end, UpdateEnd::kFailed) << without.message;
  EXPECT_NE(without.message.find("went silent while it was being caught"),
            std::string::npos)
      << without.message;

  // NRST on a host's line: released after being driven, the board starts anew.
  class Nrst final : public gpio::OutputLine {
   public:
    explicit Nrst(FlashRig* rig) : OutputLine("fake:nrst"), rig_(rig) {}
    std::vector<bool> levels;

   private:
    bool DoSet(bool active, std::string*) override {
      if (!levels.empty() && levels.back() && !active) rig_->PinReset();
      levels.push_back(active);
      return true;
    }
    FlashRig* rig_;
  } nrst(&rig);
  auto options = rig.Options();
  std::string why;
  options.after_first_hold = [&] {
    EXPECT_EQ(rig.host_sent(protocol::Function::kBootHold) > 0, true);
    // The board is held in reset while the line is low: no step of it is missed.
    EXPECT_TRUE(gpio::PulseReset(nrst, &why, gpio::kResetPulse,
                                 [&](std::chrono::nanoseconds) { rig.RunMs(10); }));
  };
  const host::UpdateResult r = rig.Update(kNode, image, options);
  EXPECT_EQ(r.end, UpdateEnd::kUpdated) << r.message;
  EXPECT_EQ(nrst.levels, (std::vector<bool>{true, false}));
  ExpectRunning(rig, kNewBuild);
}

TEST(FirmwareUpdate, APowerCutMidUploadLeavesTheBootloaderWaitingAndASecondUpdateEndsIt) {
  FlashRig rig;
  Commission(rig);
  rig.PowerOn();
  rig.RunMs(500);
  const std::vector<std::uint8_t> outside = Outside(rig.flash());
  const auto image = Checked(PackedImage(kNewBuild, 32 * 1024, 9));
  // The cut comes when the board itself reports 40 % programmed.
  std::uint16_t cut_at = 0;
  rig.watch = [&](FlashRig& r) {
    const boot::Bootloader* b = r.board() ? r.board()->bootloader() : nullptr;
    if (b != nullptr && b->state() == protocol::BootState::kReceiving &&
        b->progress_permille() >= 400) {
      cut_at = b->progress_permille();
      r.PowerOff();
    }
  };
  const host::UpdateResult cut = rig.Update(kNode, image);
  rig.watch = nullptr;
  ASSERT_GE(cut_at, 400);
  EXPECT_EQ(cut.end, UpdateEnd::kFailed);
  EXPECT_TRUE(cut.in_bootloader);
  EXPECT_NE(cut.message.find("node 3 went silent during the upload"), std::string::npos)
      << cut.message;
  EXPECT_NE(cut.message.find("run mjc flash again"), std::string::npos) << cut.message;

  rig.PowerOn(2);
  rig.RunMs(1000);
  const boot::Bootloader* stays = rig.board()->bootloader();
  ASSERT_TRUE(stays != nullptr);  // no whole image: it stays
  EXPECT_EQ(stays->reason(), protocol::StayReason::kNoValidImage);
  EXPECT_EQ(rig.board()->node(), kNode);

  const host::UpdateResult r = rig.Update(kNode, image);
  EXPECT_EQ(r.end, UpdateEnd::kUpdated) << r.message;
  ExpectRunning(rig, kNewBuild);
  EXPECT_TRUE(Outside(rig.flash()) == outside);
}

// A power cut once the board has committed the new image: the update ends on what the
// board runs when it comes back, never on a guess. Back after 2 s: the new image (its
// bootloader checked it and handed over), reported as updated; never back: said so,
// with the image whole.
TEST(FirmwareUpdate, APowerCutAfterTheCommitReportsWhatTheBoardRunsWhenItComesBack) {
  for (const bool back : {true, false}) {
    SCOPED_TRACE(back ? "power back after 2 s" : "power never back");
    FlashRig rig;
    Commission(rig);
    rig.PowerOn();
    rig.RunMs(500);
    const auto image = Checked(PackedImage(kNewBuild, 32 * 1024, 9));
    int off_ms = -1;  // since the cut
    rig.watch = [&](FlashRig& r) {
      const boot::Bootloader* b = r.board() ? r.board()->bootloader() : nullptr;
      if (off_ms < 0 && b != nullptr && b->state() == protocol::BootState::kCommitted) {
        r.PowerOff();
        off_ms = 0;
      } else if (off_ms >= 0 && r.board() == nullptr && back && ++off_ms == 2000) {
        r.PowerOn(3);
      }
    };
    const host::UpdateResult r = rig.Update(kNode, image);
    rig.watch = nullptr;
    ASSERT_GE(off_ms, 0) << "the board never reported the image committed";
    if (back) {
      EXPECT_EQ(r.end, UpdateEnd::kUpdated) << r.message;
      EXPECT_NE(r.message.find("node 3 went silent"), std::string::npos) << r.message;
      EXPECT_NE(r.message.find("came back running"), std::string::npos) << r.message;
      EXPECT_EQ(r.message.find("not whole"), std::string::npos) << r.message;
      ExpectRunning(rig, kNewBuild);
    } else {
      EXPECT_EQ(r.end, UpdateEnd::kGoneCommitted) << r.message;
      EXPECT_FALSE(r.in_bootloader);
      EXPECT_NE(r.message.find("the image is whole"), std::string::npos) << r.message;
      // Powered again later, it runs the new image.
      rig.PowerOn(4);
      rig.RunMs(1500);
      ExpectRunning(rig, kNewBuild);
    }
  }
}

TEST(FirmwareUpdate, LostFramesAndAnswersAreSentAgainFromWhereTheBoardIs) {
  FlashRig rig;
  Commission(rig);
  rig.PowerOn();
  rig.RunMs(500);
  const auto image = Checked(PackedImage(kNewBuild, 16 * 1024, 11));
  // A consecutive frame of the 5th chunk lost on its way (the board's ISO-TP times out
  // and says so), and the answer to the 20th chunk lost on its way back (the host sends
  // that chunk again, the board names the offset it expects).
  int first_frames = 0;
  bool dropped_frame = false;
  rig.drop_to_board = [&](const protocol::CanFrame& f) {
    if ((f.data[0] >> 4) == 1) ++first_frames;
    if (!dropped_frame && first_frames == 6 && (f.data[0] >> 4) == 2 &&
        (f.data[0] & 0x0F) == 3) {
      dropped_frame = true;
      return true;
    }
    return false;
  };
  int chunk_answers = 0;
  bool dropped_answer = false;
  rig.drop_to_host = [&](const protocol::CanFrame& f) {
    protocol::BootResult a;
    if (protocol::Decode(f, &a) != protocol::DecodeError::kOk ||
        a.request != protocol::BootRequest::kChunk ||
        a.error != protocol::BootError::kNone) {
      return false;
    }
    if (++chunk_answers == 20 && !dropped_answer) {
      dropped_answer = true;
      return true;
    }
    return false;
  };
  const host::UpdateResult r = rig.Update(kNode, image);
  EXPECT_TRUE(dropped_frame && dropped_answer);
  EXPECT_EQ(r.end, UpdateEnd::kUpdated) << r.message;
  EXPECT_EQ(r.chunks_resent, 2);
  ExpectRunning(rig, kNewBuild);
  std::vector<std::uint8_t> region(image.file.size());
  ASSERT_EQ(boot::AppRegion(&rig.flash(), boot::kG474Layout).Read(0, region),
            protocol::BootError::kNone);
  EXPECT_TRUE(region == image.file);
}

TEST(FirmwareUpdate, TransfersTheHostGaveUpOnWhileTheBoardRanAreSentAgain) {
  // A host too busy for the kernel's fixed 1 s wait for flow control (a loaded machine;
  // a board process starved of CPU answers late): eight chunks in a row whose first
  // frame never gets an answer in time, though the board keeps its clock. More than the
  // five failures in a row a board that refuses gets; within the transfers' own budget.
  FlashRig rig;
  Commission(rig);
  rig.PowerOn();
  rig.RunMs(500);
  const auto image = Checked(PackedImage(kNewBuild, 16 * 1024, 12));
  int first_frames = 0, dropped = 0;
  rig.drop_to_board = [&](const protocol::CanFrame& f) {
    if ((f.data[0] >> 4) != 1) return false;
    ++first_frames;
    if (first_frames >= 10 && dropped < 8) {
      ++dropped;
      return true;
    }
    return false;
  };
  const host::UpdateResult r = rig.Update(kNode, image);
  EXPECT_EQ(dropped, 8);
  EXPECT_EQ(r.end, UpdateEnd::kUpdated) << r.message;
  EXPECT_EQ(r.chunks_resent, 8);
  ExpectRunning(rig, kNewBuild);

  // A board that takes no first frame at all is still given up on, saying why.
  FlashRig deaf;
  Commission(deaf);
  deaf.PowerOn();
  deaf.RunMs(500);
  first_frames = 0;
  deaf.drop_to_board = [&](const protocol::CanFrame& f) {
    return (f.data[0] >> 4) == 1 && ++first_frames > 1;  // the Begin, then nothing
  };
  const host::UpdateResult none = deaf.Update(kNode, image);
  EXPECT_EQ(none.end, UpdateEnd::kFailed);
  EXPECT_NE(none.message.find("did not take the chunk at offset 0 in 31 transfers though "
                              "it kept running (no flow control)"),
            std::string::npos)
      << none.message;
}

TEST(FirmwareUpdate, AnImageForOtherHardwareIsRefusedAndTheOldOneRunsAgain) {
  FlashRig rig;
  Commission(rig);
  rig.PowerOn();
  rig.RunMs(500);
  const host::UpdateResult r =
      rig.Update(kNode, Checked(PackedImage(kNewBuild, 4096, 3, 2, 3)));
  EXPECT_EQ(r.end, UpdateEnd::kRefused) << r.message;
  EXPECT_EQ(
      r.message,
      "node 3 refused the image (wrong_hardware: built for hardware revisions 2..3, "
      "the board is another): nothing was written, and it runs its old image again");
  ExpectRunning(rig, kOldBuild);
}

TEST(FirmwareUpdate, ABoardWithoutAnImageIsUpdatedFromItsBootloader) {
  FlashRig rig;
  Commission(rig, false);
  rig.PowerOn();
  rig.RunMs(300);
  const boot::Bootloader* stays = rig.board()->bootloader();
  ASSERT_TRUE(stays != nullptr);
  EXPECT_EQ(stays->error(), protocol::BootError::kNoImage);
  const host::UpdateResult r =
      rig.Update(kNode, Checked(PackedImage(kNewBuild, 8192, 5)));
  EXPECT_EQ(r.end, UpdateEnd::kUpdated) << r.message;
  ExpectRunning(rig, kNewBuild);
  EXPECT_EQ(rig.host_sent(protocol::Function::kBootHold) > 0, true);
}

TEST(FirmwareUpdate, ASilentNodeIsNamedAndNothingIsDone) {
  FlashRig rig;
  Commission(rig);
  const host::UpdateResult r =
      rig.Update(kNode, Checked(PackedImage(kNewBuild, 4096, 5)));
  EXPECT_EQ(r.end, UpdateEnd::kSilent);
  EXPECT_EQ(r.message,
            "node 3 is silent (is the board powered and on the in-process bus? try mjc "
            "list); nothing was done");
  EXPECT_EQ(rig.host_sent(protocol::Function::kBootIsoTpToBoard), 0u);
  // Holds every 10 ms for the 10 s of silence, nothing else.
  EXPECT_GE(rig.host_sent(protocol::Function::kBootHold), 990u);
  EXPECT_LE(rig.host_sent(protocol::Function::kBootHold), 1010u);
}

// --- the image file, checked before anything is sent -------------------------------

std::string Refusal(std::vector<std::uint8_t> file) {
  std::string why;
  const auto image = host::CheckFirmwareImage(std::move(file), "app.bin", &why);
  EXPECT_FALSE(image);
  return why;
}

TEST(FirmwareImage, FilesThatAreNotTheJointBoardsWholeImageAreRefusedWithTheReason) {
  const auto good = PackedImage(kNewBuild, 4096, 1);
  ASSERT_TRUE(Checked(good).file.size() == good.size());
  // Truncated: the last double-word missing; or cut inside the header area.
  auto truncated = good;
  truncated.resize(good.size() - 8);
  EXPECT_EQ(Refusal(truncated),
            "app.bin: truncated: 4600 bytes, its header says 512 + 4096 = 4608");
  EXPECT_EQ(Refusal(std::vector<std::uint8_t>(good.begin(), good.begin() + 300)),
            "app.bin: truncated: 300 bytes, not even the 512-byte header area");
  // Corrupted: one image byte flipped.
  auto corrupted = good;
  corrupted[2000] ^= 0x10;
  const std::string crc = Refusal(corrupted);
  EXPECT_EQ(crc.rfind("app.bin: corrupted: the image's CRC-32 is 0x", 0), 0u) << crc;
  // Another board type, address, size; no header; a damaged header.
  EXPECT_EQ(
      Refusal(PackedImage(kNewBuild, 4096, 1, 1, 1, 2)),
      "app.bin: built for QEMU's mps2-an386 test board (board type 2), not the joint "
      "board (board type 1)");
  EXPECT_EQ(Refusal(PackedImage(kNewBuild, 4096, 1, 1, 1, 1, 0x08008200u)),
            "app.bin: linked to run at 0x08008200, not at the joint board's application "
            "address 0x08004200");
  EXPECT_EQ(Refusal(PackedImage(kNewBuild, 245248 + 8, 1)),
            "app.bin: an image of 245256 bytes, more than the joint board's application "
            "region holds (245248)");
  std::vector<std::uint8_t> elf(4096, 0x7F);
  EXPECT_EQ(Refusal(elf).rfind("app.bin: not a firmware image (no MJCI header", 0), 0u);
  auto damaged = good;
  damaged[40] ^= 1;  // the describe string, under the header's CRC
  EXPECT_EQ(Refusal(damaged),
            "app.bin: damaged image header (its CRC, version or commit mark do not check "
            "out)");
}

// mjc flash judges the file before it opens the interface: on this machine, which has
// no CAN at all, a bad file is refused for what it is and a good one only then fails on
// the interface.
int RunMjc(const std::string& args, std::string* err) {
  const std::string err_path = ::testing::TempDir() + "/mjc_flash_err.txt";
  const int status = std::system(
      (std::string(MJC_TOOL) + " " + args + " 2>" + err_path + " >/dev/null").c_str());
  err->clear();
  if (std::FILE* in = std::fopen(err_path.c_str(), "r")) {
    char buffer[512];
    for (std::size_t n; (n = std::fread(buffer, 1, sizeof buffer, in)) > 0;) {
      err->append(buffer, n);
    }
    std::fclose(in);
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

TEST(MjcFlash, BadFlagsAndBadFilesAreRefusedInOneLineBeforeTheBus) {
  const std::string dir = ::testing::TempDir();
  const auto write = [&](const std::string& name,
                         const std::vector<std::uint8_t>& bytes) {
    std::ofstream(dir + "/" + name, std::ios::binary)
        .write(reinterpret_cast<const char*>(bytes.data()),
               static_cast<std::streamsize>(bytes.size()));
    return dir + "/" + name;
  };
  const std::string good = write("good.bin", PackedImage(kNewBuild, 4096, 1));
  auto bad = PackedImage(kNewBuild, 4096, 1, 1, 1, 2);
  const std::string qemu = write("qemu.bin", bad);
  std::string err;
  EXPECT_EQ(RunMjc("flash --iface mjc-none0 --node 2 " + qemu, &err), 1);
  EXPECT_EQ(err, "mjc flash: " + qemu +
                     ": built for QEMU's mps2-an386 test board (board type 2), not the "
                     "joint board (board type 1)\n");
  EXPECT_EQ(RunMjc("flash --iface mjc-none0 --node 2 " + dir + "/none.bin", &err), 1);
  EXPECT_EQ(err, "mjc flash: " + dir + "/none.bin: no such file\n");
  EXPECT_EQ(RunMjc("flash --iface mjc-none0 " + good, &err), 2);
  EXPECT_EQ(err,
            "mjc flash: say which boards: --node N (repeat for several) or --all (see "
            "mjc flash --help)\n");
  EXPECT_EQ(RunMjc("flash --iface mjc-none0 --node 9 " + good, &err), 2);
  EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
  EXPECT_EQ(RunMjc("flash --iface mjc-none0 --node 2 --all " + good, &err), 2);
  EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
  EXPECT_EQ(RunMjc("flash --iface mjc-none0 --info " + good, &err), 2);
  EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
  // A reset line is one board's; a malformed one is a command-line error.
  EXPECT_EQ(
      RunMjc("flash --iface mjc-none0 --all --reset-line gpiochip0:3 " + good, &err), 2);
  EXPECT_EQ(err,
            "mjc flash: --reset-line is one board's NRST: give one --node (for several, "
            "--reset takes each board's line from the config file's \"reset_lines\")\n");
  EXPECT_EQ(
      RunMjc("flash --iface mjc-none0 --node 2 --reset-line gpiochip0 " + good, &err), 2);
  EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
  EXPECT_NE(err.find("is not CHIP:LINE"), std::string::npos) << err;
  // The good file passes its checks; only the interface stops it.
  EXPECT_EQ(RunMjc("flash --iface mjc-none0 --node 2 " + good, &err), 1);
  EXPECT_EQ(err.rfind("mjc flash: ", 0), 0u);
  EXPECT_EQ(err.find(good), std::string::npos) << err;
  EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
}

}  // namespace
