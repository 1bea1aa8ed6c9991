// Power cuts against the calibration store: at every operation of an update (the
// erase and each double-word program), with random garbage where the cut falls, and at
// thousands of random points over long sequences of updates. After every "reboot" the
// board must load either the last record whose save completed or the one being saved —
// never a corrupt one, never nothing once something was saved. Each power-cut test
// prints its points tried and records lost ("powercut_<kind>_points: N"); ./bench sums
// them.
#include "mjc/app/calibration_store.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "hal/sim/sim_flash.h"

namespace {

using namespace mjc;
using mjc::app::CalibrationStore;
using mjc::app::StoreResult;
using mjc::hal::SimFlash;

protocol::CalibrationRecord Record(int i) {
  protocol::CalibrationRecord r;
  r.backlash.c_right = Angle::FromRaw(300000 + i * 17);
  r.backlash.c_left = Angle::FromRaw(-250000 - i * 13);
  r.sea_stiffness = Stiffness::FromRaw(10569646 + i);
  r.joint_zero_count = static_cast<std::uint16_t>(i % 16384);
  r.fitted_at_unix_s = 1790000000u + static_cast<std::uint64_t>(i);
  return r;
}

bool Same(const protocol::CalibrationRecord& a, const protocol::CalibrationRecord& b) {
  return a.backlash.c_right == b.backlash.c_right &&
         a.backlash.c_left == b.backlash.c_left && a.sea_stiffness == b.sea_stiffness &&
         a.joint_zero_count == b.joint_zero_count &&
         a.fitted_at_unix_s == b.fitted_at_unix_s;
}

constexpr std::uint32_t kPageA = 3, kPageB = 7;

TEST(CalibrationStore, SavesLoadsAndAlternatesPages) {
  SimFlash flash(8);
  CalibrationStore store(&flash, kPageA, kPageB);
  EXPECT_FALSE(store.Load());  // erased flash: uncalibrated
  for (int i = 0; i < 5; ++i) {
    ASSERT_EQ(store.Save(Record(i)), StoreResult::kOk);
    const auto loaded = CalibrationStore(&flash, kPageA, kPageB).Load();  // a reboot
    ASSERT_TRUE(loaded);
    EXPECT_TRUE(Same(loaded->record, Record(i)));
    EXPECT_EQ(loaded->sequence, static_cast<std::uint32_t>(i + 1));
    EXPECT_EQ(loaded->page, i % 2 == 0 ? kPageA : kPageB);
  }
}

// Starting from `history` completed saves, cuts power at operation `cut` of the next
// save; returns true when the reboot loads the last completed record or the new one.
bool SurvivesCut(int history, long cut, std::uint64_t seed, bool* got_new) {
  SimFlash flash(8);
  CalibrationStore store(&flash, kPageA, kPageB);
  for (int i = 0; i < history; ++i) {
    if (store.Save(Record(i)) != StoreResult::kOk) return false;
  }
  flash.CutPowerAfter(cut, seed);
  const StoreResult result = store.Save(Record(history));
  flash.PowerOn();
  const auto loaded = CalibrationStore(&flash, kPageA, kPageB).Load();
  *got_new = loaded && Same(loaded->record, Record(history));
  if (result == StoreResult::kOk) return *got_new;  // the cut came after the save
  if (history == 0) return !loaded || *got_new;     // nothing before: nothing or the new
  return loaded && (*got_new || Same(loaded->record, Record(history - 1)));
}

TEST(CalibrationStore, PowerCutAtEveryStepOfAnUpdate) {
  // One update is 10 operations: an erase and 9 double-word programs.
  int points = 0, lost = 0, completed_new = 0;
  for (int history : {0, 1, 2}) {  // erased flash, one valid page, both pages valid
    for (long cut = 0; cut <= 10; ++cut) {
      for (std::uint64_t seed = 1; seed <= 8; ++seed) {
        bool got_new = false;
        ++points;
        if (!SurvivesCut(history, cut, seed, &got_new)) ++lost;
        if (got_new) ++completed_new;
      }
    }
  }
  EXPECT_EQ(lost, 0);
  // The new record appears only when the cut spared the last program (cut = 10: none).
  EXPECT_EQ(completed_new, 3 * 8);
  std::printf("powercut_step_points: %d\npowercut_step_lost: %d\n", points, lost);
}

TEST(CalibrationStore, PowerCutAtThousandsOfRandomPoints) {
  std::mt19937_64 rng(0xC0FFEE);
  int points = 0, lost = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    const int history = static_cast<int>(rng() % 6);
    const long cut = static_cast<long>(rng() % 11);
    bool got_new = false;
    ++points;
    if (!SurvivesCut(history, cut, rng(), &got_new)) ++lost;
  }
  EXPECT_EQ(lost, 0);
  std::printf("powercut_random_points: %d\npowercut_random_lost: %d\n", points, lost);
}

TEST(CalibrationStore, CorruptPagesAreIgnoredNotLoaded) {
  SimFlash flash(8);
  CalibrationStore store(&flash, kPageA, kPageB);
  ASSERT_EQ(store.Save(Record(1)), StoreResult::kOk);
  ASSERT_EQ(store.Save(Record(2)), StoreResult::kOk);  // page B, newest
  // A bit of the newest record's payload decayed: its CRC fails and the older record
  // wins. (Flash cannot flip a programmed bit back, so the decay is made in a copy.)
  SimFlash copy(8);
  for (std::uint32_t page : {kPageA, kPageB}) {
    for (std::uint32_t off = 0; off < 72; off += 8) {
      std::uint8_t dw[8];
      flash.Read(page, off, dw);
      std::uint64_t v = 0;
      for (int i = 7; i >= 0; --i) v = (v << 8) | dw[i];
      if (page == kPageB && off == 16) v ^= 0x10;
      copy.ProgramDoubleWord(page, off, v);
    }
  }
  const auto loaded = CalibrationStore(&copy, kPageA, kPageB).Load();
  ASSERT_TRUE(loaded);
  EXPECT_TRUE(Same(loaded->record, Record(1)));
}

TEST(SimFlash, FollowsTheG4Rules) {
  SimFlash flash(2);
  EXPECT_EQ(flash.ProgramDoubleWord(0, 4, 1),
            hal::FlashResult::kBadAddress);  // unaligned
  EXPECT_EQ(flash.ProgramDoubleWord(2, 0, 1),
            hal::FlashResult::kBadAddress);  // no page 2
  EXPECT_EQ(flash.ProgramDoubleWord(0, 0, 1), hal::FlashResult::kOk);
  EXPECT_EQ(flash.ProgramDoubleWord(0, 0, 0), hal::FlashResult::kNotErased);  // twice
  EXPECT_EQ(flash.ErasePage(0), hal::FlashResult::kOk);
  EXPECT_EQ(flash.ProgramDoubleWord(0, 0, 0), hal::FlashResult::kOk);
}

TEST(SimFlash, PersistsToItsFile) {
  const std::string path = ::testing::TempDir() + "/mjc_flash_test.bin";
  std::remove(path.c_str());
  {
    SimFlash flash(8, path);
    CalibrationStore store(&flash, kPageA, kPageB);
    ASSERT_EQ(store.Save(Record(9)), StoreResult::kOk);
  }
  SimFlash again(8, path);  // a restarted board
  const auto loaded = CalibrationStore(&again, kPageA, kPageB).Load();
  ASSERT_TRUE(loaded);
  EXPECT_TRUE(Same(loaded->record, Record(9)));
  std::remove(path.c_str());
}

std::vector<std::uint8_t> FileBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::vector<std::uint8_t> out;
  for (int c; (c = in.get()) != EOF;) out.push_back(static_cast<std::uint8_t>(c));
  return out;
}

TEST(SimFlash, WritesEachOperationWhereItChangedTheFile) {
  const std::string path = ::testing::TempDir() + "/mjc_flash_ops.bin";
  std::remove(path.c_str());
  {
    SimFlash flash(4, path);
    EXPECT_TRUE(flash.mirrored());
    // A new file is the whole flash, erased, at once.
    EXPECT_EQ(FileBytes(path), std::vector<std::uint8_t>(4 * 2048, 0xFF));
    // Bytes changed behind its back (page 3) stay as they are: a program of page 1
    // writes its own double-word only, an erase of page 2 its own page only.
    {
      std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
      f.seekp(3 * 2048 + 5);
      f.put(0x42);
    }
    ASSERT_EQ(flash.ProgramDoubleWord(1, 16, 0x0123456789ABCDEFull),
              hal::FlashResult::kOk);
    ASSERT_EQ(flash.ErasePage(2), hal::FlashResult::kOk);
    const auto bytes = FileBytes(path);
    ASSERT_EQ(bytes.size(), 4u * 2048);
    EXPECT_EQ(bytes[3 * 2048 + 5], 0x42);
    EXPECT_EQ(bytes[2048 + 16], 0xEF);
    EXPECT_EQ(bytes[2048 + 23], 0x01);
    EXPECT_EQ(flash.file_errors(), 0);
  }
  std::remove(path.c_str());
}

TEST(SimFlash, AFileOfAnotherSizeIsLeftUntouched) {
  const std::string path = ::testing::TempDir() + "/mjc_flash_other.bin";
  std::vector<std::uint8_t> other(3000, 0x5A);
  std::ofstream(path, std::ios::binary)
      .write(reinterpret_cast<const char*>(other.data()),
             static_cast<std::streamsize>(other.size()));
  std::string why;
  SimFlash flash(2, path, &why);
  EXPECT_FALSE(flash.mirrored());
  EXPECT_EQ(why, path + " holds 3000 bytes, not 4096: left untouched");
  ASSERT_EQ(flash.ErasePage(0), hal::FlashResult::kOk);
  ASSERT_EQ(flash.ProgramDoubleWord(0, 0, 7), hal::FlashResult::kOk);
  EXPECT_EQ(FileBytes(path), other);
  std::remove(path.c_str());
}

}  // namespace
