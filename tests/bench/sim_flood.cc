// The simulated board's trial under a full-rate flood, for ./bench: two flood frames
// before every tick of a whole 5-repetition trial over the in-process bus, and the
// frames the board dropped (goal 0). The rig is tests/sim/bus_trial_rig.h; the goals
// (every window, every frame counted) are asserted by tests/sim/bus_trial_test.cc.
#include <cstdio>

#include "bus_trial_rig.h"

int main() {
  using namespace mjc::bus_trial;
  constexpr int kPerTick = 2;
  Flood flood(1);
  const BoardRun run = RunTrial(&flood, kPerTick);
  if (!run.trial.completed) {
    std::fprintf(stderr, "sim_flood: the trial did not complete: %s\n",
                 run.trial.error.c_str());
    return 1;
  }
  std::printf("sim_flood_frames: %u frames (%u ticks, %d per tick)\n", run.flooded,
              run.ticks, kPerTick);
  std::printf("sim_flood_frames_dropped: %u frames (goal 0)\n", run.dropped());
  return 0;
}
