// The board identity record (node id, hardware revision) in its A/B pages: saves
// alternate, damaged pages are ignored, and a power cut at every operation of a save
// and at 2,000 random points leaves the old identity or the new one, never none (the
// sweep is identity_powercut_rig.h; ./bench's identity_powercut_* figures come from it,
// tests/bench/flash_powercut.cc).
#include "mjc/boot/identity_store.h"

#include <gtest/gtest.h>

#include "hal/sim/sim_flash.h"
#include "identity_powercut_rig.h"

namespace {

using namespace mjc::boot;
using namespace mjc::boot::test;
using mjc::hal::SimFlash;

constexpr std::uint32_t kA = kIdentityA, kB = kIdentityB;

TEST(IdentityStore, SavesLoadsAndAlternatesPages) {
  SimFlash flash(256);
  IdentityStore store(&flash, kA, kB);
  EXPECT_FALSE(store.Load());
  for (int i = 0; i < 6; ++i) {
    ASSERT_EQ(store.Save(Identity(i)), IdentityResult::kOk);
    const auto loaded = IdentityStore(&flash, kA, kB).Load();
    ASSERT_TRUE(loaded);
    EXPECT_TRUE(Same(loaded->identity, Identity(i)));
    EXPECT_EQ(loaded->page, i % 2 == 0 ? kA : kB);
  }
}

TEST(IdentityStore, RefusesWhatNoBoardCanBe) {
  SimFlash flash(256);
  IdentityStore store(&flash, kA, kB);
  EXPECT_EQ(store.Save({.node = 0, .hardware_revision = 1}), IdentityResult::kInvalid);
  EXPECT_EQ(store.Save({.node = 9, .hardware_revision = 1}), IdentityResult::kInvalid);
  EXPECT_EQ(store.Save({.node = 1, .hardware_revision = 0}), IdentityResult::kInvalid);
  EXPECT_EQ(flash.operations(), 0);
}

TEST(IdentityStore, ADamagedNewestRecordFallsBackToTheOlder) {
  SimFlash flash(256);
  IdentityStore store(&flash, kA, kB);
  ASSERT_EQ(store.Save(Identity(1)), IdentityResult::kOk);  // page A
  // Page B with a record whose CRC does not match (its node byte changed).
  ASSERT_EQ(flash.ErasePage(kB), mjc::hal::FlashResult::kOk);
  std::uint8_t a[32];
  ASSERT_EQ(flash.Read(kA, 0, a), mjc::hal::FlashResult::kOk);
  a[8] = 9;  // a newer sequence
  a[16] ^= 3;
  for (std::uint32_t off = 0; off < 32; off += 8) {
    std::uint64_t v = 0;
    for (int i = 7; i >= 0; --i) v = (v << 8) | a[off + static_cast<std::uint32_t>(i)];
    ASSERT_EQ(flash.ProgramDoubleWord(kB, off, v), mjc::hal::FlashResult::kOk);
  }
  const auto loaded = store.Load();
  ASSERT_TRUE(loaded);
  EXPECT_EQ(loaded->page, kA);
  EXPECT_TRUE(Same(loaded->identity, Identity(1)));
}

TEST(IdentityStore, PowerCutAtEveryStepAndAtRandomPoints) {
  const IdentityPowerCutSweep sweep = IdentityPowerCuts();
  EXPECT_EQ(sweep.points, 3 * 6 * 8 + 2000);
  EXPECT_EQ(sweep.lost, 0);
  // Every cut inside a save (all but the one after its end) leaves an unreadable double
  // word in the page it wrote, which the reboot's load reads: most of the sweep.
  EXPECT_GT(sweep.ecc_reads, sweep.points / 2);
}

}  // namespace
