// RecordPages, the A/B flash record both the identity and the calibration are kept in:
// the bytes on the page are the documented layout (the CRC checked against zlib's
// crc32, an implementation we did not write), saves alternate pages with a growing
// sequence, the newest valid page wins, and a page the caller does not accept or whose
// commit mark is missing is passed over, and so is a page the flash cannot read (an ECC
// error a cut left), which the next save erases. Power cuts at every step are swept
// through both stores (identity_store_test.cc, tests/unit/app's calibration power-cut
// rig).
#include "mjc/boot/record_pages.h"

#include <gtest/gtest.h>
#include <zlib.h>

#include <array>
#include <cstdint>
#include <span>

#include "hal/sim/sim_flash.h"

namespace {

using mjc::boot::RecordFormat;
using mjc::boot::RecordPages;
using mjc::boot::RecordResult;
using mjc::hal::FlashResult;
using mjc::hal::SimFlash;

constexpr std::uint32_t kA = 10, kB = 11;
constexpr RecordFormat kFormat{
    .magic = 0x54534554u, .version = 7, .payload_bytes = 16, .commit = 0xA5A5C3C3u};
using Payload = std::array<std::uint8_t, kFormat.payload_bytes>;

// The caller's check: a payload starting with 0xFF is not one it uses.
bool NotFf(std::span<const std::uint8_t> payload) { return payload[0] != 0xFF; }

Payload Numbered(std::uint8_t n) {
  Payload p{};
  for (std::size_t i = 0; i < p.size(); ++i) p[i] = static_cast<std::uint8_t>(n + i);
  return p;
}

std::uint32_t Le(const std::uint8_t* b, int n) {
  std::uint32_t v = 0;
  for (int i = n - 1; i >= 0; --i) v = (v << 8) | b[i];
  return v;
}

TEST(RecordPages, ThePageHoldsTheDocumentedLayout) {
  // Setup.
  SimFlash flash(16);
  RecordPages pages(&flash, kA, kB, kFormat, NotFf);

  // Exercise.
  ASSERT_EQ(pages.Save(Numbered(3)), RecordResult::kOk);

  // Verify: magic, version, length, sequence 1, reserved 0, payload, CRC-32 of all
  // before it, commit mark; 40 bytes for a 16-byte payload.
  std::array<std::uint8_t, 40> b{};
  ASSERT_EQ(flash.Read(kA, 0, b), FlashResult::kOk);
  EXPECT_EQ(RecordPages::RecordBytes(kFormat), 40u);
  EXPECT_EQ(Le(&b[0], 4), kFormat.magic);
  EXPECT_EQ(Le(&b[4], 2), kFormat.version);
  EXPECT_EQ(Le(&b[6], 2), kFormat.payload_bytes);
  EXPECT_EQ(Le(&b[8], 4), 1u);
  EXPECT_EQ(Le(&b[12], 4), 0u);
  const Payload expected = Numbered(3);
  for (std::size_t i = 0; i < expected.size(); ++i) EXPECT_EQ(b[16 + i], expected[i]);
  EXPECT_EQ(Le(&b[32], 4), crc32(crc32(0L, Z_NULL, 0), b.data(), 32));
  EXPECT_EQ(Le(&b[36], 4), kFormat.commit);
}

TEST(RecordPages, SavesAlternatePagesAndTheNewestWins) {
  SimFlash flash(16);
  RecordPages pages(&flash, kA, kB, kFormat, NotFf);
  Payload out{};
  EXPECT_FALSE(pages.Load(out));
  for (std::uint8_t i = 1; i <= 5; ++i) {
    ASSERT_EQ(pages.Save(Numbered(i)), RecordResult::kOk);
    const auto found = RecordPages(&flash, kA, kB, kFormat, NotFf).Load(out);
    ASSERT_TRUE(found);
    EXPECT_EQ(found->sequence, i);
    EXPECT_EQ(found->page, i % 2 == 1 ? kA : kB);
    EXPECT_EQ(out, Numbered(i));
  }
}

TEST(RecordPages, APayloadTheCallerRefusesIsPassedOver) {
  // Setup: the older record is good, the newer one intact but refused by the caller.
  SimFlash flash(16);
  RecordPages pages(&flash, kA, kB, kFormat, NotFf);
  ASSERT_EQ(pages.Save(Numbered(1)), RecordResult::kOk);  // page A
  Payload refused = Numbered(2);
  refused[0] = 0xFF;
  // Saving it fails its own verification, and the older record stays the newest valid.
  EXPECT_EQ(pages.Save(refused), RecordResult::kVerifyFailed);

  // Exercise.
  Payload out{};
  const auto found = pages.Load(out);

  // Verify.
  ASSERT_TRUE(found);
  EXPECT_EQ(found->page, kA);
  EXPECT_EQ(out, Numbered(1));
}

TEST(RecordPages, APageWithoutItsCommitMarkDoesNotCount) {
  // Setup: page B holds everything of a newer record but its last double-word (the
  // CRC and the commit mark), as a power cut just before it leaves it.
  SimFlash flash(16);
  RecordPages pages(&flash, kA, kB, kFormat, NotFf);
  ASSERT_EQ(pages.Save(Numbered(1)), RecordResult::kOk);
  ASSERT_EQ(pages.Save(Numbered(2)), RecordResult::kOk);  // page B
  std::array<std::uint8_t, 40> b{};
  ASSERT_EQ(flash.Read(kB, 0, b), FlashResult::kOk);
  ASSERT_EQ(flash.ErasePage(kB), FlashResult::kOk);
  for (std::uint32_t offset = 0; offset < 32; offset += 8) {
    std::uint64_t v = 0;
    for (int i = 7; i >= 0; --i) v = (v << 8) | b[offset + static_cast<std::uint32_t>(i)];
    ASSERT_EQ(flash.ProgramDoubleWord(kB, offset, v), FlashResult::kOk);
  }

  // Exercise.
  Payload out{};
  const auto found = pages.Load(out);

  // Verify: the older record on page A.
  ASSERT_TRUE(found);
  EXPECT_EQ(found->page, kA);
  EXPECT_EQ(out, Numbered(1));
}

}  // namespace

namespace {

TEST(RecordPages, AnUnreadablePageLosesToTheOtherAndIsErasedByTheNextSave) {
  // Two records (A: 1, B: 2), then a save of 3 into A cut in its first program: A's
  // erase completed, its first double word now reads as an ECC double error (the flash
  // fails the read, as the G4 image's driver does after the NMI).
  SimFlash flash(16);
  RecordPages pages(&flash, kA, kB, kFormat, NotFf);
  ASSERT_EQ(pages.Save(Numbered(1)), RecordResult::kOk);
  ASSERT_EQ(pages.Save(Numbered(2)), RecordResult::kOk);
  flash.CutPowerAfter(1, 5);  // the erase of A completes, its first program is cut
  EXPECT_EQ(pages.Save(Numbered(3)), RecordResult::kFlashError);
  flash.PowerOn();
  std::array<std::uint8_t, 8> first{};
  ASSERT_EQ(flash.Read(kA, 0, first), FlashResult::kHardwareError);

  RecordPages rebooted(&flash, kA, kB, kFormat, NotFf);
  Payload got{};
  const auto found = rebooted.Load(got);
  ASSERT_TRUE(found);
  EXPECT_EQ(found->page, kB);
  EXPECT_EQ(got, Numbered(2));
  EXPECT_EQ(rebooted.unreadable(), 1u) << "page A named";

  // The next save goes to A (B holds the newest valid record): erased, readable again.
  ASSERT_EQ(rebooted.Save(Numbered(4)), RecordResult::kOk);
  EXPECT_EQ(flash.Read(kA, 0, first), FlashResult::kOk);
  RecordPages again(&flash, kA, kB, kFormat, NotFf);
  const auto after = again.Load(got);
  ASSERT_TRUE(after);
  EXPECT_EQ(after->page, kA);
  EXPECT_EQ(got, Numbered(4));
  EXPECT_EQ(again.unreadable(), 0u);
}

}  // namespace
