// The board identity record (node id, hardware revision) in its A/B pages: saves
// alternate, damaged pages are ignored, and a power cut at every operation of a save
// and at 2,000 random points leaves the old identity or the new one, never none.
#include "mjc/boot/identity_store.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <random>

#include "hal/sim/sim_flash.h"

namespace {

using namespace mjc::boot;
using mjc::hal::SimFlash;

constexpr std::uint32_t kA = 252, kB = 253;

BoardIdentity Identity(int i) {
  return {.node = static_cast<std::uint8_t>(1 + i % 8),
          .hardware_revision = static_cast<std::uint8_t>(1 + i % 200)};
}
bool Same(const BoardIdentity& a, const BoardIdentity& b) {
  return a.node == b.node && a.hardware_revision == b.hardware_revision;
}

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

bool SurvivesCut(int history, long cut, std::uint64_t seed) {
  SimFlash flash(256);
  IdentityStore store(&flash, kA, kB);
  for (int i = 0; i < history; ++i) {
    if (store.Save(Identity(i)) != IdentityResult::kOk) return false;
  }
  flash.CutPowerAfter(cut, seed);
  const IdentityResult result = store.Save(Identity(history));
  flash.PowerOn();
  const auto loaded = IdentityStore(&flash, kA, kB).Load();
  const bool got_new = loaded && Same(loaded->identity, Identity(history));
  if (result == IdentityResult::kOk) return got_new;
  if (history == 0) return !loaded || got_new;
  return loaded && (got_new || Same(loaded->identity, Identity(history - 1)));
}

TEST(IdentityStore, PowerCutAtEveryStepAndAtRandomPoints) {
  int points = 0, lost = 0;
  for (int history : {0, 1, 2}) {
    for (long cut = 0; cut <= 5; ++cut) {  // an erase and 4 double-words
      for (std::uint64_t seed = 1; seed <= 8; ++seed) {
        ++points;
        if (!SurvivesCut(history, cut, seed)) ++lost;
      }
    }
  }
  std::mt19937_64 rng(0x1D1D);
  for (int trial = 0; trial < 2000; ++trial) {
    ++points;
    if (!SurvivesCut(static_cast<int>(rng() % 6), static_cast<long>(rng() % 6), rng())) {
      ++lost;
    }
  }
  EXPECT_EQ(lost, 0);
  std::printf("identity_powercut_points: %d\nidentity_powercut_lost: %d\n", points, lost);
}

}  // namespace
