// Power cuts against the calibration store on the simulated flash: at every operation
// of an update (the erase and each double-word program), with random garbage where the
// cut falls, and at thousands of random points over long sequences of updates. After
// every "reboot" the board must load either the last record whose save completed or
// the one being saved — never a corrupt one, never nothing once something was saved —
// although the simulated flash fails every read of a double word the cut left (its ECC
// does not match, as on the STM32G4); and the save after the reboot must succeed and be
// what loads (it erases the page the cut damaged).
// Shared by tests/unit/app/calibration_store_test.cc (the goals, asserted) and
// tests/bench/calibration_powercut.cc (the powercut_* figures of ./bench).
#pragma once

#include <cstdint>

#include "mjc/protocol/calibration_record.h"

namespace mjc::calibration_powercut {

// The store's two pages on an 8-page simulated flash.
inline constexpr std::uint32_t kPageA = 3, kPageB = 7;

// The i-th of a sequence of distinct records.
protocol::CalibrationRecord Record(int i);
bool Same(const protocol::CalibrationRecord& a, const protocol::CalibrationRecord& b);

// Starting from `history` completed saves, cuts power at operation `cut` of the next
// save; true when the reboot loads the last completed record or the new one.
// `got_new`: the reboot loaded the new record.
// `ecc_read`: the reboot's load met a page the flash could not read.
bool SurvivesCut(int history, long cut, std::uint64_t seed, bool* got_new,
                 bool* ecc_read);

struct Sweep {
  int points = 0;         // power cuts tried
  int lost = 0;           // reboots that found neither the old record nor the new one
  int completed_new = 0;  // reboots that loaded the new record
  int ecc_reads = 0;      // reboots whose load met a page the cut left unreadable
};

// Every step of an update (one update is 10 operations: an erase and 9 double-word
// programs; cut 10 comes after the last) over erased flash, one valid page and both
// pages valid, each with 8 seeds for the garbage: 264 points.
Sweep EveryStep();
// 2,000 random points: 0-5 completed saves before, a random step, a random seed.
Sweep RandomPoints();

}  // namespace mjc::calibration_powercut
