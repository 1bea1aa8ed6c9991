#include "identity_powercut_rig.h"

#include <random>

#include "hal/sim/sim_flash.h"

namespace mjc::boot::test {

namespace {

// Starting from `history` completed saves, cuts power at operation `cut` of the next
// save; true when the reboot loads the last completed identity or the new one, and the
// save after the reboot succeeds and loads. `*ecc_read`: the reboot's load met a page
// the flash could not read.
bool SurvivesCut(int history, long cut, std::uint64_t seed, bool* ecc_read) {
  hal::SimFlash flash(256);
  IdentityStore store(&flash, kIdentityA, kIdentityB);
  for (int i = 0; i < history; ++i) {
    if (store.Save(Identity(i)) != IdentityResult::kOk) return false;
  }
  flash.CutPowerAfter(cut, seed);
  const IdentityResult result = store.Save(Identity(history));
  flash.PowerOn();
  const long ecc_before = flash.ecc_errors();
  IdentityStore rebooted(&flash, kIdentityA, kIdentityB);
  const auto loaded = rebooted.Load();
  *ecc_read = flash.ecc_errors() > ecc_before;
  if (*ecc_read != (rebooted.unreadable_pages() != 0)) return false;  // named as met
  const bool got_new = loaded && Same(loaded->identity, Identity(history));
  bool kept = false;
  if (result == IdentityResult::kOk) {
    kept = got_new;
  } else if (history == 0) {
    kept = !loaded || got_new;
  } else {
    kept = loaded && (got_new || Same(loaded->identity, Identity(history - 1)));
  }
  if (!kept) return false;
  // The next save goes over whatever the cut damaged.
  if (rebooted.Save(Identity(history + 1)) != IdentityResult::kOk) return false;
  const auto after = IdentityStore(&flash, kIdentityA, kIdentityB).Load();
  return after && Same(after->identity, Identity(history + 1));
}

}  // namespace

BoardIdentity Identity(int i) {
  return {.node = static_cast<std::uint8_t>(1 + i % 8),
          .hardware_revision = static_cast<std::uint8_t>(1 + i % 200)};
}

bool Same(const BoardIdentity& a, const BoardIdentity& b) {
  return a.node == b.node && a.hardware_revision == b.hardware_revision;
}

IdentityPowerCutSweep IdentityPowerCuts() {
  IdentityPowerCutSweep sweep;
  for (int history : {0, 1, 2}) {
    for (long cut = 0; cut <= 5; ++cut) {  // an erase and 4 double-words
      for (std::uint64_t seed = 1; seed <= 8; ++seed) {
        ++sweep.points;
        bool ecc_read = false;
        if (!SurvivesCut(history, cut, seed, &ecc_read)) ++sweep.lost;
        if (ecc_read) ++sweep.ecc_reads;
      }
    }
  }
  std::mt19937_64 rng(0x1D1D);
  for (int trial = 0; trial < 2000; ++trial) {
    ++sweep.points;
    bool ecc_read = false;
    const int history = static_cast<int>(rng() % 6);
    const long cut = static_cast<long>(rng() % 6);
    if (!SurvivesCut(history, cut, rng(), &ecc_read)) ++sweep.lost;
    if (ecc_read) ++sweep.ecc_reads;
  }
  return sweep;
}

}  // namespace mjc::boot::test
