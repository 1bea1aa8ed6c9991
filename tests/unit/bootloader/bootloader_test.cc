// The bootloader's logic on the host: the decision at reset (image check, stay request,
// boot attempts, hold window), the update protocol (ISO-TP intake, chunk and flash
// rules, commit), every refusal, and that nothing outside the application region is
// ever erased or programmed. Time is the board's own clock, stepped by the test.
#include "mjc/boot/bootloader.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "boot_rig.h"
#include "hal/sim/sim_flash.h"
#include "mjc/protocol/crc32.h"
#include "mjc/protocol/little_endian.h"

namespace {

using namespace mjc;
using namespace mjc::boot;
using namespace mjc::boot::test;
using hal::SimFlash;
using protocol::BootError;
using protocol::BootRequest;
using protocol::BootState;
using protocol::StayReason;

constexpr std::uint32_t kPages = 256;

BootHandoff ZeroHandoff() { return BootHandoff{}; }

protocol::CanFrame Hold(std::uint8_t node = kNode,
                        std::uint32_t key = protocol::kBootHoldKey) {
  protocol::BootHold h;
  h.key = key;
  return protocol::Encode(h, node);
}

// ---- the decision at reset -----------------------------------------------------------

TEST(BootDecision, AValidImageBootsWhenTheHoldWindowEnds) {
  SimFlash flash(kPages);
  const auto file = MakeFile(MakeImage(5000, 1));
  Install(flash, file);
  BootHandoff handoff = ZeroHandoff();
  Board board(&flash, &handoff);
  EXPECT_EQ(board.Start(), BootAction::kNone);
  EXPECT_EQ(board.boot.state(), BootState::kHoldWindow);
  // It says who it is and where it is.
  const auto info = board.Take<protocol::BoardInfo>();
  ASSERT_EQ(info.size(), 1u);
  EXPECT_EQ(info[0].image, protocol::ImageKind::kBootloader);
  EXPECT_EQ(info[0].build, 0xB0071234u);
  const auto status = board.Take<protocol::BootStatus>();
  ASSERT_EQ(status.size(), 1u);
  EXPECT_EQ(status[0].state, BootState::kHoldWindow);
  // 200 ms of the board's clock, to the millisecond.
  for (int ms = 1; ms < 200; ++ms) ASSERT_EQ(board.Step(), BootAction::kNone) << ms;
  EXPECT_EQ(board.Step(), BootAction::kBoot);
  EXPECT_EQ(board.boot.boot_address(), 0x08004200u);
  EXPECT_EQ(BootAttempts(handoff, board.boot.image().header.image_crc), 1u);
}

TEST(BootDecision, AHoldInTheWindowKeepsTheBootloader) {
  SimFlash flash(kPages);
  Install(flash, MakeFile(MakeImage(5000, 1)));
  BootHandoff handoff = ZeroHandoff();
  Board board(&flash, &handoff);
  (void)board.Start();
  for (int ms = 0; ms < 150; ++ms) ASSERT_EQ(board.Step(), BootAction::kNone);
  board.Send(Hold());
  EXPECT_EQ(board.Step(), BootAction::kNone);
  EXPECT_EQ(board.boot.state(), BootState::kReady);
  EXPECT_EQ(board.boot.reason(), StayReason::kHoldFrame);
  const auto r = board.LastResult();
  ASSERT_TRUE(r);
  EXPECT_EQ(r->request, BootRequest::kHold);
  EXPECT_EQ(r->error, BootError::kNone);
  for (int ms = 0; ms < 5000; ++ms) ASSERT_EQ(board.Step(), BootAction::kNone);
  EXPECT_EQ(BootAttempts(handoff, board.boot.image().header.image_crc), 0u);
  // It keeps saying so, every 100 ms.
  const auto status = board.Take<protocol::BootStatus>();
  EXPECT_GE(status.size(), 50u);
  EXPECT_EQ(status.back().reason, StayReason::kHoldFrame);
  EXPECT_GT(status.back().tick_ms, 5000u) << "the status carries the board's clock";
  EXPECT_LE(board.now_ms - status.back().tick_ms, 100u);
}

TEST(BootDecision, HoldsForAnotherNodeOrWithoutTheKeyDoNotCount) {
  SimFlash flash(kPages);
  Install(flash, MakeFile(MakeImage(5000, 1)));
  BootHandoff handoff = ZeroHandoff();
  Board board(&flash, &handoff);
  (void)board.Start();
  board.Send(Hold(kNode + 1));
  board.Send(Hold(kNode, 0x12345678u));
  EXPECT_EQ(board.Step(), BootAction::kNone);
  EXPECT_EQ(board.boot.state(), BootState::kHoldWindow);
  const auto r = board.LastResult();
  ASSERT_TRUE(r);
  EXPECT_EQ(r->error, BootError::kBadRequest) << "the wrong key is answered, not obeyed";
  BootAction a = BootAction::kNone;
  while (a == BootAction::kNone) a = board.Step();
  EXPECT_EQ(a, BootAction::kBoot);
  EXPECT_EQ(board.now_ms, 200u);
}

TEST(BootDecision, NoImageOrABadOneStaysAndSaysWhy) {
  struct Case {
    std::vector<std::uint8_t> file;
    BootError expected;
  };
  const auto image = MakeImage(3000, 2);
  std::vector<Case> cases;
  cases.push_back({{}, BootError::kNoImage});
  auto flipped = MakeFile(image);
  flipped[kHeaderArea + 1234] ^= 0x40;
  cases.push_back({flipped, BootError::kImageCrc});
  cases.push_back({MakeFile(image, 2), BootError::kWrongBoard});
  cases.push_back({MakeFile(image, kBoardType, 2, 4), BootError::kWrongHardware});
  auto bad_vectors = image;
  protocol::PutLe(&bad_vectors[4], 0x08004200u + 0x100u, 4);  // not Thumb
  cases.push_back({MakeFile(bad_vectors), BootError::kBadVectors});
  auto bad_stack = image;
  protocol::PutLe(&bad_stack[0], 0x08001000u, 4);  // not RAM
  cases.push_back({MakeFile(bad_stack), BootError::kBadVectors});
  auto torn = MakeFile(image);
  torn[130] = 0;  // inside the header area, outside the header: harmless
  cases.push_back({torn, BootError::kNone});
  auto bad_header = MakeFile(image);
  bad_header[20] ^= 1;  // the load address, under the header's CRC
  cases.push_back({bad_header, BootError::kBadHeader});
  for (const Case& c : cases) {
    SimFlash flash(kPages);
    if (!c.file.empty()) Install(flash, c.file);
    BootHandoff handoff = ZeroHandoff();
    Board board(&flash, &handoff);
    (void)board.Start();
    if (c.expected == BootError::kNone) {
      EXPECT_EQ(board.boot.state(), BootState::kHoldWindow);
      continue;
    }
    EXPECT_EQ(board.boot.state(), BootState::kReady);
    EXPECT_EQ(board.boot.reason(), StayReason::kNoValidImage);
    EXPECT_EQ(board.boot.error(), c.expected);
    for (int ms = 0; ms < 1000; ++ms) ASSERT_EQ(board.Step(), BootAction::kNone);
    const auto status = board.Take<protocol::BootStatus>();
    ASSERT_FALSE(status.empty());
    EXPECT_EQ(status.back().error, c.expected);
    // Asked to boot it anyway, it refuses.
    HostUpdate host;
    const auto r = host.Command(board, BootRequest::kBoot);
    ASSERT_TRUE(r);
    EXPECT_EQ(r->error, BootError::kNothingToBoot);
  }
}

TEST(BootDecision, AHeaderTheFlashCannotReadIsNoImageAndTheNextUpdateMends) {
  // An update cut while it programmed the header's double words (the STM32G4 leaves
  // the cut double word with an ECC double error; the simulated flash fails its read,
  // as the G474 driver does once its NMI handler took the error).
  const auto file = MakeFile(MakeImage(3000, 21));
  long operations = 0;
  {
    SimFlash count(kPages);
    SpyFlash spy(&count);
    BootHandoff handoff = ZeroHandoff();
    Board board(&spy, &handoff);
    (void)board.Start();
    HostUpdate host;
    ASSERT_TRUE(host.Run(board, file));
    operations = static_cast<long>(spy.ops.size());
  }
  SimFlash flash(kPages);
  BootHandoff handoff = ZeroHandoff();
  {
    flash.CutPowerAfter(operations - 1, 3);  // the header's last double word
    Board board(&flash, &handoff);
    (void)board.Start();
    HostUpdate host;
    EXPECT_FALSE(host.Run(board, file));
    flash.PowerOn();
  }
  std::array<std::uint8_t, 8> dw{};
  ASSERT_EQ(flash.Read(8, 120, dw), hal::FlashResult::kHardwareError);
  {
    Board board(&flash, &handoff);
    EXPECT_EQ(board.Start(), BootAction::kNone);
    EXPECT_EQ(board.boot.state(), BootState::kReady);
    EXPECT_EQ(board.boot.reason(), StayReason::kNoValidImage);
    EXPECT_EQ(board.boot.error(), BootError::kUnreadable);
    const auto status = board.Take<protocol::BootStatus>();
    ASSERT_FALSE(status.empty());
    EXPECT_EQ(status.back().error, BootError::kUnreadable);
    // On the bus and ready: the update goes through (its Begin erases the header's
    // page first) and the image boots.
    HostUpdate host;
    ASSERT_TRUE(host.Run(board, file));
  }
  Board board(&flash, &handoff);
  (void)board.Start();
  EXPECT_EQ(board.boot.state(), BootState::kHoldWindow);
}

// ---- the stay request ----------------------------------------------------------------

TEST(StayRequest, CountsOnceAndOnlyAfterASoftwareReset) {
  SimFlash flash(kPages);
  Install(flash, MakeFile(MakeImage(4000, 3)));
  BootHandoff handoff = ZeroHandoff();
  RequestBootloader(handoff);
  {
    Board board(&flash, &handoff);
    (void)board.Start(/*software_reset=*/true);
    EXPECT_EQ(board.boot.state(), BootState::kReady);
    EXPECT_EQ(board.boot.reason(), StayReason::kRequested);
  }
  {
    Board board(&flash, &handoff);  // the next reset: taken already
    (void)board.Start(true);
    EXPECT_EQ(board.boot.state(), BootState::kHoldWindow);
  }
  RequestBootloader(handoff);
  {
    Board board(&flash, &handoff);  // a watchdog or pin reset: ignored, and taken
    (void)board.Start(false);
    EXPECT_EQ(board.boot.state(), BootState::kHoldWindow);
  }
  {
    Board board(&flash, &handoff);  // so a later software reset does not find it
    (void)board.Start(true);
    EXPECT_EQ(board.boot.state(), BootState::kHoldWindow);
  }
}

TEST(StayRequest, AnyDamagedWordVoidsIt) {
  for (int word = 0; word < 3; ++word) {
    for (std::uint32_t bit = 0; bit < 32; ++bit) {
      BootHandoff h = ZeroHandoff();
      RequestBootloader(h);
      std::uint32_t* w[] = {&h.stay_magic, &h.stay_reason, &h.stay_crc};
      *w[word] ^= 1u << bit;
      EXPECT_FALSE(TakeStayRequest(h, true)) << word << " " << bit;
    }
  }
}

// RAM after power-on holds anything: no pattern of it makes a stay request or a boot
// loop (seeded; 2^-64 per pattern by construction, here 200,000 patterns).
TEST(StayRequest, RandomRamNeverCounts) {
  std::mt19937_64 rng(0xB007);
  int requests = 0, loops = 0;
  for (int i = 0; i < 200000; ++i) {
    BootHandoff h;
    std::uint32_t* words = &h.stay_magic;
    for (int k = 0; k < 8; ++k) words[k] = static_cast<std::uint32_t>(rng());
    if (i % 4 == 0) h.stay_magic = kStayMagic;  // even with the right magic
    if (i % 4 == 1) h.attempts_magic = kAttemptsMagic;
    const std::uint32_t crc = h.attempts_image_crc;
    if (BootAttempts(h, crc) != 0) ++loops;
    if (TakeStayRequest(h, true)) ++requests;
    EXPECT_EQ(h.stay_magic, 0u) << "taken";
  }
  EXPECT_EQ(requests, 0);
  EXPECT_EQ(loops, 0);
}

// ---- the boot attempts (a watchdog reset loop)
// -----------------------------------------

// Resets the board `n` times, each time letting the window pass: the actions seen.
std::vector<BootAction> Resets(hal::Flash& flash, BootHandoff& handoff, int n,
                               bool confirm) {
  std::vector<BootAction> actions;
  for (int i = 0; i < n; ++i) {
    Board board(&flash, &handoff);
    BootAction a = board.Start();
    for (int ms = 0; ms < 300 && a == BootAction::kNone; ++ms) a = board.Step();
    actions.push_back(a);
    if (confirm && a == BootAction::kBoot) ConfirmHealthyBoot(handoff);
  }
  return actions;
}

TEST(BootAttempts, ThreeUnconfirmedStartsThenTheBootloaderStays) {
  SimFlash flash(kPages);
  Install(flash, MakeFile(MakeImage(4000, 4)));
  BootHandoff handoff = ZeroHandoff();
  const auto actions = Resets(flash, handoff, 5, /*confirm=*/false);
  EXPECT_EQ(actions, (std::vector<BootAction>{BootAction::kBoot, BootAction::kBoot,
                                              BootAction::kBoot, BootAction::kNone,
                                              BootAction::kNone}));
  Board board(&flash, &handoff);
  (void)board.Start();
  EXPECT_EQ(board.boot.reason(), StayReason::kBootLoop);
  const auto status = board.Take<protocol::BootStatus>();
  ASSERT_EQ(status.size(), 1u);
  EXPECT_EQ(status[0].reason, StayReason::kBootLoop);
  // The host may try again: a Boot gives the image its attempts afresh.
  HostUpdate host;
  const auto r = host.Command(board, BootRequest::kBoot);
  ASSERT_TRUE(r);
  EXPECT_EQ(r->error, BootError::kNone);
  BootAction a = BootAction::kNone;
  for (int ms = 0; ms < 100 && a == BootAction::kNone; ++ms) a = board.Step();
  EXPECT_EQ(a, BootAction::kReset);
  EXPECT_EQ(Resets(flash, handoff, 1, false), std::vector<BootAction>{BootAction::kBoot});
}

TEST(BootAttempts, AConfirmedImageNeverStays) {
  SimFlash flash(kPages);
  Install(flash, MakeFile(MakeImage(4000, 5)));
  BootHandoff handoff = ZeroHandoff();
  const auto actions = Resets(flash, handoff, 10, /*confirm=*/true);
  EXPECT_EQ(actions, std::vector<BootAction>(10, BootAction::kBoot));
}

TEST(BootAttempts, ANewImageStartsFromZero) {
  SimFlash flash(kPages);
  Install(flash, MakeFile(MakeImage(4000, 6)));
  BootHandoff handoff = ZeroHandoff();
  (void)Resets(flash, handoff, 4, false);  // the first image loops
  Install(flash, MakeFile(MakeImage(4000, 7)));
  EXPECT_EQ(Resets(flash, handoff, 1, false), std::vector<BootAction>{BootAction::kBoot});
}

// ---- updates -------------------------------------------------------------------------

// Flash with recognisable contents outside the application region: the bootloader's
// pages, the spare bank, identity and calibration pages.
void FillOutside(SimFlash& flash) {
  for (std::uint32_t page = 0; page < kPages; ++page) {
    if (page >= 8 && page < 128) continue;
    for (std::uint32_t off = 0; off < 2048; off += 8) {
      (void)flash.ProgramDoubleWord(page, off,
                                    0x0123456789ABCDEFull ^ (page * 2048 + off));
    }
  }
}
std::vector<std::uint8_t> Outside(SimFlash& flash) {
  std::vector<std::uint8_t> all;
  std::vector<std::uint8_t> page(2048);
  for (std::uint32_t p = 0; p < kPages; ++p) {
    if (p >= 8 && p < 128) continue;
    (void)flash.Read(p, 0, page);
    all.insert(all.end(), page.begin(), page.end());
  }
  return all;
}

TEST(Update, ReplacesTheImageAndBootsIt) {
  SimFlash sim(kPages);
  FillOutside(sim);
  const auto old_file = MakeFile(MakeImage(30000, 8));
  Install(sim, old_file);
  const auto outside = Outside(sim);
  SpyFlash flash(&sim);
  BootHandoff handoff = ZeroHandoff();
  const auto new_file = MakeFile(MakeImage(9000, 9));
  {
    Board board(&flash, &handoff);
    (void)board.Start();
    board.Send(Hold());
    (void)board.Step();
    HostUpdate host;
    ASSERT_TRUE(host.Run(board, new_file));
    EXPECT_EQ(board.boot.state(), BootState::kCommitted);
    EXPECT_EQ(board.boot.progress_permille(), 1000);
    BootAction a = BootAction::kNone;
    for (int ms = 0; ms < 100 && a == BootAction::kNone; ++ms) a = board.Step();
    EXPECT_EQ(a, BootAction::kReset);
    EXPECT_GE(board.now_ms, 20u) << "the answer leaves before the reset";
  }
  // The flash rules: only region pages (8..127), each erased once before it is
  // programmed; the header's page first; the header's last double-word last.
  ASSERT_FALSE(flash.ops.empty());
  EXPECT_TRUE(flash.ops.front().erase);
  EXPECT_EQ(flash.ops.front().page, 8u);
  EXPECT_FALSE(flash.ops.back().erase);
  EXPECT_EQ(flash.ops.back().page, 8u);
  EXPECT_EQ(flash.ops.back().offset, 120u);
  std::vector<int> erased(kPages, 0);
  for (const auto& op : flash.ops) {
    ASSERT_GE(op.page, 8u);
    ASSERT_LT(op.page, 128u);
    if (op.erase) {
      ++erased[op.page];
    } else {
      ASSERT_EQ(erased[op.page], 1) << "programmed page " << op.page << " erased once";
    }
  }
  EXPECT_EQ(Outside(sim), outside);
  EXPECT_EQ(RegionBytes(sim, new_file.size()), new_file);
  // The reset starts the new image.
  Board board(&flash, &handoff);
  (void)board.Start();
  EXPECT_EQ(board.boot.state(), BootState::kHoldWindow);
  ImageHeader expected;
  ASSERT_EQ(CheckImageFile(new_file, &expected), ImageCheck::kValid);
  EXPECT_EQ(board.boot.image().header.image_crc, expected.image_crc);
}

TEST(Update, SmallChunksAndProgressReports) {
  SimFlash flash(kPages);
  BootHandoff handoff = ZeroHandoff();
  Board board(&flash, &handoff);
  (void)board.Start();
  EXPECT_EQ(board.boot.reason(), StayReason::kNoValidImage);
  const auto file = MakeFile(MakeImage(4096, 10));
  HostUpdate host;
  ASSERT_TRUE(host.Request(board, BeginRequest(file)));
  EXPECT_EQ(board.boot.reason(), StayReason::kUpdate);
  const auto image = std::span<const std::uint8_t>(file).subspan(kHeaderArea);
  for (std::uint32_t at = 0; at < image.size(); at += 8) {
    const auto r = host.Request(board, ChunkRequest(at, image.subspan(at, 8)));
    ASSERT_TRUE(r && r->error == BootError::kNone) << at;
    EXPECT_EQ(r->next_offset, at + 8);
    if (at == 2048 - 8) {
      EXPECT_EQ(board.boot.progress_permille(), 500);
    }
  }
  ASSERT_EQ(host.Command(board, BootRequest::kCommit)->error, BootError::kNone);
  EXPECT_EQ(board.boot.state(), BootState::kCommitted);
}

TEST(Update, AWrongImageIsRefusedBeforeAnythingIsErased) {
  SimFlash sim(kPages);
  const auto installed = MakeFile(MakeImage(6000, 11));
  Install(sim, installed);
  SpyFlash flash(&sim);
  BootHandoff handoff = ZeroHandoff();
  Board board(&flash, &handoff);
  (void)board.Start();
  board.Send(Hold());
  (void)board.Step();
  const auto image = MakeImage(6000, 12);
  auto too_long = MakeFile(image);
  protocol::PutLe(&too_long[12], 240 * 1024, 4);  // more than the region holds
  protocol::PutLe(&too_long[120], protocol::Crc32(std::span(too_long).first(120)), 4);
  const std::pair<std::vector<std::uint8_t>, BootError> refused[] = {
      {MakeFile(image, 2), BootError::kWrongBoard},
      {MakeFile(image, kBoardType, 3, 9), BootError::kWrongHardware},
      {too_long, BootError::kBadLength},
      {std::vector<std::uint8_t>(600, 0xFF), BootError::kNoImage},
  };
  HostUpdate host;
  for (const auto& [file, error] : refused) {
    const auto r = host.Request(board, BeginRequest(file));
    ASSERT_TRUE(r);
    EXPECT_EQ(r->request, BootRequest::kBegin);
    EXPECT_EQ(r->error, error);
  }
  // A begin of the wrong length, chunks and commits without a begin.
  EXPECT_EQ(host.Request(board, std::vector<std::uint8_t>(40, 2))->error,
            BootError::kBadRequest);
  EXPECT_EQ(host.Request(board, ChunkRequest(0, std::span(image).first(64)))->error,
            BootError::kNotReceiving);
  EXPECT_EQ(host.Command(board, BootRequest::kCommit)->error, BootError::kNotReceiving);
  EXPECT_TRUE(flash.ops.empty()) << "nothing erased or programmed";
  EXPECT_EQ(board.boot.image().check, ImageCheck::kValid);
  // And the installed image still boots.
  EXPECT_EQ(host.Command(board, BootRequest::kBoot)->error, BootError::kNone);
}

TEST(Update, ChunksMustComeInOrderWholeAndWithinTheImage) {
  SimFlash flash(kPages);
  BootHandoff handoff = ZeroHandoff();
  Board board(&flash, &handoff);
  (void)board.Start();
  const auto file = MakeFile(MakeImage(1000, 13));  // 1000 bytes of image
  const auto image = std::span<const std::uint8_t>(file).subspan(kHeaderArea);
  HostUpdate host;
  ASSERT_EQ(host.Request(board, BeginRequest(file))->error, BootError::kNone);
  auto r = host.Request(board, ChunkRequest(8, image.subspan(8, 8)));
  EXPECT_EQ(r->error, BootError::kUnexpectedOffset);
  EXPECT_EQ(r->next_offset, 0u);
  EXPECT_EQ(host.Request(board, ChunkRequest(0, image.subspan(0, 12)))->error,
            BootError::kBadChunk);
  EXPECT_EQ(host.Request(board, ChunkRequest(0, std::span<const std::uint8_t>()))->error,
            BootError::kBadChunk);
  ASSERT_EQ(host.Request(board, ChunkRequest(0, image.subspan(0, 248)))->error,
            BootError::kNone);
  // The same chunk again (its answer was lost): the board says where it is.
  r = host.Request(board, ChunkRequest(0, image.subspan(0, 248)));
  EXPECT_EQ(r->error, BootError::kUnexpectedOffset);
  EXPECT_EQ(r->next_offset, 248u);
  for (std::uint32_t at = 248; at < 992; at += 248) {
    ASSERT_EQ(host.Request(board, ChunkRequest(at, image.subspan(at, 248)))->error,
              BootError::kNone);
  }
  // A commit before the end: refused, the update goes on.
  EXPECT_EQ(host.Command(board, BootRequest::kCommit)->error, BootError::kIncomplete);
  EXPECT_EQ(board.boot.state(), BootState::kReceiving);
  // Past the image's end (8 bytes are left).
  std::vector<std::uint8_t> beyond(image.begin() + 992, image.end());
  beyond.resize(16, 0);
  EXPECT_EQ(host.Request(board, ChunkRequest(992, beyond))->error, BootError::kBadChunk);
  ASSERT_EQ(host.Request(board, ChunkRequest(992, image.subspan(992, 8)))->error,
            BootError::kNone);
  EXPECT_EQ(host.Command(board, BootRequest::kCommit)->error, BootError::kNone);
}

TEST(Update, ATruncatedUpdateLeavesNoBootableImage) {
  SimFlash flash(kPages);
  Install(flash, MakeFile(MakeImage(8000, 14)));
  BootHandoff handoff = ZeroHandoff();
  const auto file = MakeFile(MakeImage(8000, 15));
  {
    Board board(&flash, &handoff);
    (void)board.Start(true);
    board.Send(Hold());
    (void)board.Step();
    HostUpdate host;
    ASSERT_EQ(host.Request(board, BeginRequest(file))->error, BootError::kNone);
    const auto image = std::span<const std::uint8_t>(file).subspan(kHeaderArea);
    for (std::uint32_t at = 0; at < 4000; at += 248) {
      ASSERT_EQ(host.Request(board, ChunkRequest(at, image.subspan(at, 248)))->error,
                BootError::kNone);
    }
    // The host goes away here; the board is reset.
  }
  Board board(&flash, &handoff);
  (void)board.Start();
  EXPECT_EQ(board.boot.state(), BootState::kReady);
  EXPECT_EQ(board.boot.reason(), StayReason::kNoValidImage);
  EXPECT_EQ(board.boot.error(), BootError::kNoImage);
  HostUpdate host;
  ASSERT_TRUE(host.Run(board, file)) << "and it takes the image again";
}

TEST(Update, AnImageCorruptedOnTheWayIsNotCommitted) {
  SimFlash flash(kPages);
  BootHandoff handoff = ZeroHandoff();
  Board board(&flash, &handoff);
  (void)board.Start();
  const auto file = MakeFile(MakeImage(3000, 16));
  auto sent = file;
  sent[kHeaderArea + 2000] ^= 0x08;  // what the board receives differs in one bit
  HostUpdate host;
  ASSERT_EQ(host.Request(board, BeginRequest(file))->error, BootError::kNone);
  const auto image = std::span<const std::uint8_t>(sent).subspan(kHeaderArea);
  for (std::uint32_t at = 0; at < image.size(); at += 248) {
    const std::size_t n = std::min<std::size_t>(248, image.size() - at);
    ASSERT_EQ(host.Request(board, ChunkRequest(at, image.subspan(at, n)))->error,
              BootError::kNone);
  }
  EXPECT_EQ(host.Command(board, BootRequest::kCommit)->error, BootError::kImageCrc);
  EXPECT_EQ(board.boot.state(), BootState::kReady);
  EXPECT_EQ(board.boot.error(), BootError::kImageCrc);
  std::vector<std::uint8_t> header(kHeaderSize);
  (void)flash.Read(8, 0, header);
  EXPECT_EQ(header, std::vector<std::uint8_t>(kHeaderSize, 0xFF)) << "no header written";
  EXPECT_EQ(host.Command(board, BootRequest::kBoot)->error, BootError::kNothingToBoot);
  ASSERT_TRUE(host.Run(board, file)) << "the right image is taken afterwards";
}

TEST(Update, AFlashErrorEndsTheUpdateAndANewOneSucceeds) {
  SimFlash flash(kPages);
  BootHandoff handoff = ZeroHandoff();
  Board board(&flash, &handoff);
  (void)board.Start();
  const auto file = MakeFile(MakeImage(5000, 17));
  HostUpdate host;
  ASSERT_EQ(host.Request(board, BeginRequest(file))->error, BootError::kNone);
  const auto image = std::span<const std::uint8_t>(file).subspan(kHeaderArea);
  ASSERT_EQ(host.Request(board, ChunkRequest(0, image.subspan(0, 248)))->error,
            BootError::kNone);
  // The double-word the next chunk starts with, programmed behind the bootloader's
  // back: its program fails (the flash refuses a double-word that is not erased).
  ASSERT_EQ(flash.ProgramDoubleWord(8, 512 + 248, 0), hal::FlashResult::kOk);
  EXPECT_EQ(host.Request(board, ChunkRequest(248, image.subspan(248, 248)))->error,
            BootError::kFlashError);
  EXPECT_EQ(board.boot.state(), BootState::kReady);
  EXPECT_EQ(board.boot.reason(), StayReason::kUpdate);
  ASSERT_TRUE(host.Run(board, file));
}

TEST(Update, AbortAndBootWithoutAnImage) {
  SimFlash flash(kPages);
  BootHandoff handoff = ZeroHandoff();
  Board board(&flash, &handoff);
  (void)board.Start();
  const auto file = MakeFile(MakeImage(3000, 18));
  HostUpdate host;
  ASSERT_EQ(host.Request(board, BeginRequest(file))->error, BootError::kNone);
  EXPECT_EQ(host.Command(board, BootRequest::kBoot)->error, BootError::kNothingToBoot);
  EXPECT_EQ(host.Command(board, BootRequest::kAbort)->error, BootError::kNone);
  EXPECT_EQ(board.boot.state(), BootState::kReady);
  EXPECT_EQ(host.Request(board, ChunkRequest(0, std::span(file).subspan(512, 8)))->error,
            BootError::kNotReceiving);
  EXPECT_EQ(host.Command(board, BootRequest::kChunk)->error, BootError::kBadRequest);
}

// ---- the ISO-TP intake
// -----------------------------------------------------------------

TEST(IsoTpIntake, FlowControlOnTheBootloadersChannelAndBrokenTransfers) {
  SimFlash flash(kPages);
  BootHandoff handoff = ZeroHandoff();
  Board board(&flash, &handoff);
  (void)board.Start();
  const auto file = MakeFile(MakeImage(3000, 19));
  const auto begin = BeginRequest(file);
  const auto frames =
      IsoTpSegments(protocol::MakeId(0x3C, kNode), std::span<const std::uint8_t>(begin));
  ASSERT_GT(frames.size(), 2u);
  // The first frame: a clear-to-send on 0x3D.
  board.can.from_board.clear();
  board.Send(frames[0]);
  (void)board.Step();
  ASSERT_FALSE(board.can.from_board.empty());
  const auto& fc = board.can.from_board.front();
  EXPECT_EQ(fc.id, protocol::MakeId(0x3D, kNode));
  EXPECT_EQ(fc.data[0], 0x30);
  // A consecutive frame out of sequence: the transfer is dropped and reported.
  board.Send(frames[2]);
  (void)board.Step();
  auto r = board.LastResult();
  ASSERT_TRUE(r);
  EXPECT_EQ(r->error, BootError::kTransfer);
  // A transfer that stops: N_Cr (1 s of the board's clock) ends it.
  board.Send(frames[0]);
  board.Send(frames[1]);
  (void)board.Step();
  const std::uint32_t last_frame_ms = board.now_ms;
  board.can.from_board.clear();
  r.reset();
  while (!r && board.now_ms < last_frame_ms + 2000) {
    (void)board.Step();
    r = board.LastResult();
  }
  ASSERT_TRUE(r);
  EXPECT_EQ(r->error, BootError::kTransfer);
  EXPECT_EQ(board.now_ms - last_frame_ms, 1001u) << "N_Cr: more than 1000 ms";
  // A first frame larger than the receiver's buffer: flow control "overflow".
  std::vector<std::uint8_t> big(300, 3);
  board.can.from_board.clear();
  board.Send(IsoTpSegments(protocol::MakeId(0x3C, kNode), big)[0]);
  (void)board.Step();
  ASSERT_FALSE(board.can.from_board.empty());
  EXPECT_EQ(board.can.from_board.front().data[0], 0x32);
  // Whole again, it goes through.
  HostUpdate host;
  EXPECT_EQ(host.Request(board, begin)->error, BootError::kNone);
}

TEST(IsoTpIntake, FramesQueueWhenTheControllerIsFull) {
  SimFlash flash(kPages);
  BootHandoff handoff = ZeroHandoff();
  Board board(&flash, &handoff);
  board.can.tx_room = 0;  // the TX FIFO is full for now
  (void)board.Start();    // erased flash: it stays, with a status every 100 ms
  for (int ms = 0; ms < 1000; ++ms) (void)board.Step();
  EXPECT_TRUE(board.can.from_board.empty());
  board.can.tx_room = 100;
  (void)board.Step();
  // Kept in order; what did not fit in the outbox is counted, never half-sent.
  const auto info = board.Take<protocol::BoardInfo>();
  EXPECT_EQ(info.size(), 1u);
  EXPECT_EQ(board.can.from_board.size(), Bootloader::kOutboxFrames - 1);
  EXPECT_GT(board.boot.frames_dropped(), 0u);
}

// ---- the region guard ----------------------------------------------------------------

TEST(AppRegion, RefusesEveryAddressOutsideTheApplicationRegion) {
  SimFlash sim(kPages);
  SpyFlash flash(&sim);
  AppRegion region(&flash, kG474Layout);
  EXPECT_EQ(region.size(), 120u * 2048);
  const std::uint32_t size = region.size();
  for (std::uint32_t offset : {size, size + 8, size + 2048, 0xFFFFFFF8u, 0x80000000u}) {
    EXPECT_EQ(region.ErasePageAt(offset), BootError::kOutOfRegion) << offset;
    EXPECT_EQ(region.Program(offset, 0), BootError::kOutOfRegion) << offset;
  }
  EXPECT_EQ(region.Program(size - 4, 0), BootError::kOutOfRegion);
  EXPECT_EQ(region.Program(4, 0), BootError::kOutOfRegion) << "not 8-aligned";
  std::array<std::uint8_t, 16> buffer{};
  EXPECT_EQ(region.Read(size - 8, buffer), BootError::kOutOfRegion);
  EXPECT_TRUE(flash.ops.empty());
  // Inside: its pages 8 and 127, no other.
  EXPECT_EQ(region.ErasePageAt(0), BootError::kNone);
  EXPECT_EQ(region.ErasePageAt(size - 1), BootError::kNone);
  EXPECT_EQ(region.Program(size - 8, 0), BootError::kNone);
  ASSERT_EQ(flash.ops.size(), 3u);
  EXPECT_EQ(flash.ops[0].page, 8u);
  EXPECT_EQ(flash.ops[1].page, 127u);
  EXPECT_EQ(flash.ops[2].page, 127u);
  EXPECT_EQ(flash.ops[2].offset, 2040u);
}

}  // namespace
