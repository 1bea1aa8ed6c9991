// The calibration store: saves alternate pages, a corrupt page is ignored, the record
// persists in the simulated flash's file, and power cuts at every operation of an
// update and at thousands of random points lose nothing (the sweeps are in
// calibration_powercut_rig.h; ./bench's powercut_* figures come from the same sweeps,
// tests/bench/calibration_powercut.cc).
#include "mjc/app/calibration_store.h"

#include <gtest/gtest.h>

#include <cstdio>

#include "calibration_powercut_rig.h"
#include "hal/sim/sim_flash.h"

namespace {

using namespace mjc;
using namespace mjc::calibration_powercut;
using mjc::app::CalibrationStore;
using mjc::app::StoreResult;
using mjc::hal::SimFlash;

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

TEST(CalibrationStore, PowerCutAtEveryStepOfAnUpdate) {
  const Sweep sweep = EveryStep();
  EXPECT_EQ(sweep.points, 3 * 11 * 8);
  EXPECT_EQ(sweep.lost, 0);
  // A cut inside the save's first 9 operations (the erase and the header/payload
  // double words the load reads) leaves an unreadable page the reboot meets.
  EXPECT_GT(sweep.ecc_reads, sweep.points / 2);
  // The new record appears only when the cut spared the last program (cut = 10: none).
  EXPECT_EQ(sweep.completed_new, 3 * 8);
}

TEST(CalibrationStore, PowerCutAtThousandsOfRandomPoints) {
  const Sweep sweep = RandomPoints();
  EXPECT_EQ(sweep.points, 2000);
  EXPECT_EQ(sweep.lost, 0);
  EXPECT_GT(sweep.ecc_reads, sweep.points / 2);
  // Some cuts came after the save's last operation, and some before it.
  EXPECT_GT(sweep.completed_new, 0);
  EXPECT_LT(sweep.completed_new, sweep.points);
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

TEST(CalibrationStore, PersistsInTheSimulatedFlashsFile) {
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

}  // namespace
