// What every Cortex-M4 benchmark image shares: the two markers scripts/cm4-instructions
// counts the instructions between, and the announcement that names each run on the
// semihosting output ("bench: <name>", which the script pairs with its count).
//
// The markers are defined here, not only declared: each benchmark image is one source
// file, which includes this header once.
#pragma once

#include "semihost.h"

extern "C" {
// Not inlined and not empty to the optimiser, so their addresses bracket each run.
__attribute__((noinline)) void mjc_bench_begin() { asm volatile("" ::: "memory"); }
__attribute__((noinline)) void mjc_bench_end() { asm volatile("" ::: "memory"); }
}

namespace mjc::bench {

// A measured run, by its stable name (./bench prints "<name>_cm4: <count> instructions").
struct Entry {
  const char* name;
  void (*run)();
};

inline void Announce(const char* name) {
  qemu::SemihostWrite("bench: ");
  qemu::SemihostWrite(name);
  qemu::SemihostWrite("\n");
}

// The entry announced, then run between the markers.
inline void Measure(const Entry& entry) {
  Announce(entry.name);
  mjc_bench_begin();
  entry.run();
  mjc_bench_end();
}

}  // namespace mjc::bench
