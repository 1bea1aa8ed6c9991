// Power cuts against the board identity record's A/B pages on the simulated flash: at
// every operation of a save (an erase and 4 double-words) and at 2,000 random points;
// each reboot must find the old identity or the new one, never none, although the
// simulated flash fails every read of a double word the cut left (its ECC does not
// match, as on the STM32G4); and the next save must succeed and be what loads (it
// erases the page the cut damaged). Shared by
// tests/unit/bootloader/identity_store_test.cc (the goal, asserted) and
// tests/bench/flash_powercut.cc (./bench's identity_powercut_* figures).
#pragma once

#include <cstdint>

#include "mjc/boot/identity_store.h"

namespace mjc::boot::test {

// The identity pages on a 256-page simulated flash.
inline constexpr std::uint32_t kIdentityA = 252, kIdentityB = 253;

// The i-th of a sequence of distinct identities.
BoardIdentity Identity(int i);
bool Same(const BoardIdentity& a, const BoardIdentity& b);

struct IdentityPowerCutSweep {
  int points = 0;  // power cuts tried
  int lost = 0;    // reboots that found neither the old identity nor the new one
  // Cuts whose damage the reboot's read met (a page the flash could not read, named
  // by the store): the sweep's proof that such reads are survived (goal ≫ 0).
  int ecc_reads = 0;
};

// Every step (0-2 saves before, 6 cut points, 8 seeds) and 2,000 random points.
IdentityPowerCutSweep IdentityPowerCuts();

}  // namespace mjc::boot::test
