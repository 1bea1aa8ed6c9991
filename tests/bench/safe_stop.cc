// Time from each fault's cause to a disabled bridge on the simulated board, for
// ./bench: one "safe_stop_ticks_<fault>: N ticks (X ms)" line per fault. The causes,
// and the tick each count starts from, are in tests/sim/safe_stop_rig.h; the goals are
// asserted by tests/sim/fault_stop_test.cc.
#include <cstdio>

#include "safe_stop_rig.h"

int main() {
  using namespace mjc::safe_stop;
  int failed = 0;
  for (const FaultCase c : kAllCases) {
    const Measurement m = Measure(c);
    if (!m.error.empty()) {
      std::fprintf(stderr, "safe_stop: %s: %s\n", Name(c), m.error.c_str());
      ++failed;
      continue;
    }
    std::printf("safe_stop_ticks_%s: %lld ticks (%.1f ms)\n", Name(c),
                static_cast<long long>(m.stop_ticks()), m.stop_ms());
  }
  return failed == 0 ? 0 : 1;
}
