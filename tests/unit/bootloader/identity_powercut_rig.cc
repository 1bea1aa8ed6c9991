#include "identity_powercut_rig.h"

#include <random>

#include "hal/sim/sim_flash.h"

namespace mjc::boot::test {

namespace {

// Starting from `history` completed saves, cuts power at operation `cut` of the next
// save; true when the reboot loads the last completed identity or the new one.
bool SurvivesCut(int history, long cut, std::uint64_t seed) {
  hal::SimFlash flash(256);
  IdentityStore store(&flash, kIdentityA, kIdentityB);
  for (int i = 0; i < history; ++i) {
    if (store.Save(Identity(i)) != IdentityResult::kOk) return false;
  }
  flash.CutPowerAfter(cut, seed);
  const IdentityResult result = store.Save(Identity(history));
  flash.PowerOn();
  const auto loaded = IdentityStore(&flash, kIdentityA, kIdentityB).Load();
  const bool got_new = loaded && Same(loaded->identity, Identity(history));
  if (result == IdentityResult::kOk) return got_new;
  if (history == 0) return !loaded || got_new;
  return loaded && (got_new || Same(loaded->identity, Identity(history - 1)));
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
        if (!SurvivesCut(history, cut, seed)) ++sweep.lost;
      }
    }
  }
  std::mt19937_64 rng(0x1D1D);
  for (int trial = 0; trial < 2000; ++trial) {
    ++sweep.points;
    if (!SurvivesCut(static_cast<int>(rng() % 6), static_cast<long>(rng() % 6), rng())) {
      ++sweep.lost;
    }
  }
  return sweep;
}

}  // namespace mjc::boot::test
