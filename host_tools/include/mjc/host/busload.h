// Worst-case CAN bus load of the Maestro's boards: every frame the protocol sends, at
// its configured rate, timed with worst-case bit stuffing.
//
// Frame times (11-bit identifiers):
//  - classical CAN: 47 + 8n bits (SOF … IFS) plus ⌊(34 + 8n − 1)/4⌋ stuff bits in the
//    34 + 8n stuffable bits (the standard worst case: 135 bits for 8 bytes, 55 for 0);
//  - CAN FD with bit-rate switching: at the nominal rate SOF … BRS (17 bits, up to 4
//    stuff bits) and CRC delimiter … IFS (13 bits); at the data rate ESI, DLC and the
//    payload (5 + 8n bits, up to ⌈(5 + 8n)/4⌉ stuff bits), the stuff count (4) and CRC
//    (17 bits up to 16 bytes, 21 above) with their fixed stuff bits (1 + ⌊(3 + crc)/4⌋).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "mjc/protocol/params.h"

namespace mjc::host {

struct BusTiming {
  bool fd = true;
  double nominal_bps = 1e6;
  double data_bps = 5e6;  // FD data phase (bit-rate switching); ignored for classical
};

// Worst-case duration of one frame with `payload_bytes` (classical: 0..8; FD: a legal
// FD length) on `timing`, seconds.
double FrameTimeS(int payload_bytes, const BusTiming& timing);

// How a board sends its angle samples: one TelemetryAngles frame each (classical CAN),
// or TelemetryAngleBatch::kSamples to a TelemetryAngleBatch frame (CAN FD). A board
// batches when its link is FD, so the link's layout is LinkLayout(timing).
enum class AngleLayout : std::uint8_t { kSingle, kBatched };
AngleLayout LinkLayout(const BusTiming& timing);

// Bus time of one angle sample in `layout` on `timing`: its frame's, shared by the
// samples the frame carries, seconds.
double AngleFrameS(AngleLayout layout, const BusTiming& timing);

struct BusLoadLine {
  std::string message;
  int payload_bytes = 0;
  double hz_per_board = 0;
  double load_fraction = 0;  // of the bus, all boards together
};

struct BusLoad {
  std::vector<BusLoadLine> lines;
  double total_fraction = 0;
};

// The load of `boards` boards transmitting at `rates` (the board's own telemetry
// schedule) and their window summaries, plus the host's heartbeat to each board.
// Payload lengths are the message table's (protocol/messages.h); the angles go in
// `layout` (the link's by default).
BusLoad ComputeBusLoad(const protocol::TelemetryRates& rates, int boards,
                       const BusTiming& timing, AngleLayout layout);
inline BusLoad ComputeBusLoad(const protocol::TelemetryRates& rates, int boards,
                              const BusTiming& timing) {
  return ComputeBusLoad(rates, boards, timing, LinkLayout(timing));
}

// The highest rate of the angle telemetry (samples per second and board, in `layout`)
// that keeps `boards` boards' total load at or below `budget` with the other rates as
// given; 0 if even the rest does not fit.
double MaxTelemetryHz(protocol::TelemetryRates rates, int boards, const BusTiming& timing,
                      double budget, AngleLayout layout);
inline double MaxTelemetryHz(const protocol::TelemetryRates& rates, int boards,
                             const BusTiming& timing, double budget) {
  return MaxTelemetryHz(rates, boards, timing, budget, LinkLayout(timing));
}

std::string FormatBusLoad(const BusLoad& load, const BusTiming& timing, int boards,
                          AngleLayout layout);
inline std::string FormatBusLoad(const BusLoad& load, const BusTiming& timing,
                                 int boards) {
  return FormatBusLoad(load, timing, boards, LinkLayout(timing));
}

// The whole report of `mjc busload`: `boards` boards at the default rates on CAN FD
// (nominal/data bit rates; angles batched, as a board on an FD link sends them) and on
// classical CAN at the nominal rate (one sample a frame), the FD load the classical
// layout would cause, and the highest angle-telemetry rate each link keeps within a
// 50 % budget.
std::string BusLoadReport(int boards, double nominal_bps, double data_bps);

// ./bench's bus-load figures, one "name: value unit" line each (README, Benchmarks):
// busload_8x1khz_fd_pct, the worst-case load of 8 boards at the default rates on CAN FD
// 1/5 Mbit/s (angles batched), and classic_1m_max_telemetry_hz, the highest
// angle-telemetry rate 8 boards keep within 50 % of classical CAN at 1 Mbit/s.
std::string BusLoadFigures();

}  // namespace mjc::host
