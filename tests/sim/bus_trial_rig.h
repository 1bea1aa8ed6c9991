// A trial over the protocol without a kernel: the simulated board (app + CAN node on
// the plant) and the host's BoardClient with mjc trial's runner, joined by the
// in-process bus the paper's scenarios use (sim::BusBoard, lock-stepped); optionally
// under a full-rate frame flood. Shared by tests/sim/bus_trial_test.cc
// (the goals, asserted) and tests/bench/sim_flood.cc (the sim_flood_* figures of
// ./bench).
//
// The flood: besides the host's own traffic, the board's CAN node receives `per_tick`
// more frames before every 100 µs tick (two: 20,000 frames/s, about what CAN FD at
// 1/5 Mbit/s carries with 8-byte payloads) — other boards' telemetry, commands for
// other nodes, malformed frames for this node, parameter reads that each need a reply,
// and random identifiers and lengths.
#pragma once

#include <cstdint>
#include <random>
#include <vector>

#include "mjc/app/can_node.h"
#include "mjc/host/trial_runner.h"
#include "mjc/protocol/messages.h"

namespace mjc::bus_trial {

// The flood's frames, in a fixed rotation so every kind is equally represented; every
// random generator seeded with a constant.
class Flood {
 public:
  explicit Flood(std::uint8_t node) : node_(node) {}

  protocol::CanFrame Next();
  std::uint32_t malformed_sent() const { return malformed_sent_; }
  std::uint32_t param_reads_sent() const { return param_reads_sent_; }

 private:
  std::uint8_t node_;
  std::uint32_t n_ = 0;
  std::uint32_t malformed_sent_ = 0;
  std::uint32_t param_reads_sent_ = 0;
  std::mt19937 rng_{20261121};
};

// What one board-side run saw, besides the trial the host assembled.
struct BoardRun {
  host::BoardTrial trial;
  std::vector<double> truth_energy;  // the plant's interface energy, index: board tick
  app::CanNodeCounters counters;
  std::uint32_t ticks = 0;
  std::uint32_t tick_gaps = 0;  // ticks whose counter did not advance by exactly one
  std::uint32_t from_host = 0;
  std::uint32_t flooded = 0;
  std::uint32_t param_replies = 0;
  int progress_lines = 0;            // the host's per-window progress callbacks
  std::uint64_t host_malformed = 0;  // frames the host could not decode
  bool faulted = false;

  // Frames the board dropped: its transmit queue and its event queue.
  std::uint32_t dropped() const { return counters.tx_dropped + counters.events_dropped; }
};

// Five 15° repetitions at 0.5 Hz on subject 1's hand, calibrated with the plant's own
// slack; `flood` (may be null) adds `per_tick` frames before every tick. A few seconds
// of wall time.
BoardRun RunTrial(Flood* flood, int per_tick);

}  // namespace mjc::bus_trial
