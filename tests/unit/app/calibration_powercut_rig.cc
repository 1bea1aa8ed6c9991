#include "calibration_powercut_rig.h"

#include <random>

#include "hal/sim/sim_flash.h"
#include "mjc/app/calibration_store.h"

namespace mjc::calibration_powercut {

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

bool SurvivesCut(int history, long cut, std::uint64_t seed, bool* got_new,
                 bool* ecc_read) {
  SimFlash flash(8);
  CalibrationStore store(&flash, kPageA, kPageB);
  for (int i = 0; i < history; ++i) {
    if (store.Save(Record(i)) != StoreResult::kOk) return false;
  }
  flash.CutPowerAfter(cut, seed);
  const StoreResult result = store.Save(Record(history));
  flash.PowerOn();
  const long ecc_before = flash.ecc_errors();
  CalibrationStore rebooted(&flash, kPageA, kPageB);
  const auto loaded = rebooted.Load();
  *ecc_read = flash.ecc_errors() > ecc_before;
  if (*ecc_read != (rebooted.unreadable_pages() != 0)) return false;  // named as met
  *got_new = loaded && Same(loaded->record, Record(history));
  bool kept = false;
  if (result == StoreResult::kOk) {
    kept = *got_new;  // the cut came after the save
  } else if (history == 0) {
    kept = !loaded || *got_new;  // nothing before: nothing or the new
  } else {
    kept = loaded && (*got_new || Same(loaded->record, Record(history - 1)));
  }
  if (!kept) return false;
  // The next save goes over whatever the cut damaged.
  if (rebooted.Save(Record(history + 1)) != StoreResult::kOk) return false;
  const auto after = CalibrationStore(&flash, kPageA, kPageB).Load();
  return after && Same(after->record, Record(history + 1));
}

Sweep EveryStep() {
  Sweep s;
  for (int history : {0, 1, 2}) {  // erased flash, one valid page, both pages valid
    for (long cut = 0; cut <= 10; ++cut) {
      for (std::uint64_t seed = 1; seed <= 8; ++seed) {
        bool got_new = false, ecc_read = false;
        ++s.points;
        if (!SurvivesCut(history, cut, seed, &got_new, &ecc_read)) ++s.lost;
        if (got_new) ++s.completed_new;
        if (ecc_read) ++s.ecc_reads;
      }
    }
  }
  return s;
}

Sweep RandomPoints() {
  std::mt19937_64 rng(0xC0FFEE);
  Sweep s;
  for (int trial = 0; trial < 2000; ++trial) {
    const int history = static_cast<int>(rng() % 6);
    const long cut = static_cast<long>(rng() % 11);
    bool got_new = false, ecc_read = false;
    ++s.points;
    if (!SurvivesCut(history, cut, rng(), &got_new, &ecc_read)) ++s.lost;
    if (got_new) ++s.completed_new;
    if (ecc_read) ++s.ecc_reads;
  }
  return s;
}

}  // namespace mjc::calibration_powercut
