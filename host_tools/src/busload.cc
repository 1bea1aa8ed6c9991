#include "mjc/host/busload.h"

#include <cmath>
#include <cstdio>

#include "mjc/host/board_client.h"
#include "mjc/protocol/messages.h"

namespace mjc::host {

double FrameTimeS(int n, const BusTiming& t) {
  if (!t.fd) {
    const int bits = 47 + 8 * n + (34 + 8 * n - 1) / 4;
    return bits / t.nominal_bps;
  }
  const int nominal_bits = 17 + 4 + 13;
  const int crc = n <= 16 ? 17 : 21;
  const int payload = 5 + 8 * n;
  const int data_bits = payload + (payload + 3) / 4 + 4 + crc + 1 + (3 + crc) / 4;
  return nominal_bits / t.nominal_bps + data_bits / t.data_bps;
}

namespace {

// Frames per second each board sends of every window part: two windows (flexion and
// extension) per cycle, at most 2 Hz cycles in the paper's protocols.
constexpr double kWindowsHz = 4.0;
// The host's heartbeat to each board, Hz.
constexpr double kHostHeartbeatHz = 1000.0 / kHostHeartbeatPeriod.count();

}  // namespace

AngleLayout LinkLayout(const BusTiming& t) {
  return t.fd ? AngleLayout::kBatched : AngleLayout::kSingle;
}

double AngleFrameS(AngleLayout layout, const BusTiming& t) {
  using protocol::Message;
  using protocol::TelemetryAngleBatch;
  if (layout == AngleLayout::kSingle) {
    return FrameTimeS(Message<protocol::TelemetryAngles>::kLength, t);
  }
  return FrameTimeS(Message<TelemetryAngleBatch>::kLength, t) /
         static_cast<double>(TelemetryAngleBatch::kSamples);
}

BusLoad ComputeBusLoad(const protocol::TelemetryRates& r, int boards, const BusTiming& t,
                       AngleLayout layout) {
  BusLoad load;
  auto add = [&]<class M>(M, double hz, const char* suffix = "") {
    const int bytes = protocol::Message<M>::kLength;
    BusLoadLine line{std::string(protocol::Message<M>::kName) + suffix, bytes, hz,
                     hz * boards * FrameTimeS(bytes, t)};
    load.total_fraction += line.load_fraction;
    load.lines.push_back(line);
  };
  if (layout == AngleLayout::kBatched) {
    add(protocol::TelemetryAngleBatch{},
        r.angles_hz / static_cast<double>(protocol::TelemetryAngleBatch::kSamples));
  } else {
    add(protocol::TelemetryAngles{}, r.angles_hz);
  }
  add(protocol::TelemetryTorque{}, r.torque_hz);
  add(protocol::TelemetryPower{}, r.power_hz);
  add(protocol::TelemetryEnergy{}, r.energy_hz);
  add(protocol::TelemetryControl{}, r.control_hz);
  add(protocol::Heartbeat{}, r.heartbeat_hz);
  add(protocol::BoardInfo{}, r.info_hz);
  add(protocol::WindowStart{}, kWindowsHz);
  add(protocol::WindowHeader{}, kWindowsHz);
  add(protocol::WindowEnergy{}, kWindowsHz);
  add(protocol::WindowWork{}, kWindowsHz);
  add(protocol::WindowPeaks{}, kWindowsHz);
  add(protocol::WindowTicks{}, kWindowsHz);
  add(protocol::WindowFit{}, kWindowsHz);
  add(protocol::WindowFitResidual{}, kWindowsHz);
  add(protocol::HostHeartbeat{}, kHostHeartbeatHz, " (host)");
  return load;
}

double MaxTelemetryHz(protocol::TelemetryRates rates, int boards, const BusTiming& timing,
                      double budget, AngleLayout layout) {
  rates.angles_hz = 0;
  const double rest = ComputeBusLoad(rates, boards, timing, layout).total_fraction;
  if (rest >= budget) return 0;
  return (budget - rest) / (boards * AngleFrameS(layout, timing));
}

std::string FormatBusLoad(const BusLoad& load, const BusTiming& t, int boards,
                          AngleLayout layout) {
  char line[200];
  std::string out;
  if (t.fd) {
    std::snprintf(line, sizeof line,
                  "CAN FD %.0f/%.0f kbit/s, %d boards, worst-case stuffing, %s\n",
                  t.nominal_bps / 1e3, t.data_bps / 1e3, boards,
                  layout == AngleLayout::kBatched ? "angles batched (TelemetryAngleBatch)"
                                                  : "one angle sample a frame");
  } else {
    std::snprintf(line, sizeof line,
                  "classical CAN %.0f kbit/s, %d boards, worst-case stuffing\n",
                  t.nominal_bps / 1e3, boards);
  }
  out += line;
  std::snprintf(line, sizeof line, "  %-34s %5s %9s %10s %8s\n", "message", "bytes",
                "Hz/board", "frame (us)", "load");
  out += line;
  for (const auto& l : load.lines) {
    std::snprintf(line, sizeof line, "  %-34s %5d %9.0f %10.1f %7.2f%%\n",
                  l.message.c_str(), l.payload_bytes, l.hz_per_board,
                  FrameTimeS(l.payload_bytes, t) * 1e6, 100.0 * l.load_fraction);
    out += line;
  }
  std::snprintf(line, sizeof line, "  %-34s %5s %9s %10s %7.2f%%\n", "total", "", "", "",
                100.0 * load.total_fraction);
  out += line;
  return out;
}

std::string BusLoadReport(int boards, double nominal_bps, double data_bps) {
  const protocol::TelemetryRates defaults;
  const BusTiming fd{true, nominal_bps, data_bps};
  const BusTiming classic{false, nominal_bps, nominal_bps};
  // What the boards send: batches on CAN FD, single samples on classical CAN.
  std::string out = FormatBusLoad(ComputeBusLoad(defaults, boards, fd), fd, boards);
  out += FormatBusLoad(ComputeBusLoad(defaults, boards, classic), classic, boards);
  char line[200];
  // The FD bus with the classical layout, for comparison: what batching saves.
  std::snprintf(
      line, sizeof line,
      "one angle sample a frame on CAN FD (the classical layout) would load "
      "%.2f%%\n",
      100.0 * ComputeBusLoad(defaults, boards, fd, AngleLayout::kSingle).total_fraction);
  out += line;
  std::snprintf(
      line, sizeof line,
      "highest angle-telemetry rate within 50%%: FD %.0f Hz, classical %.0f Hz\n",
      MaxTelemetryHz(defaults, boards, fd, 0.5),
      MaxTelemetryHz(defaults, boards, classic, 0.5));
  return out + line;
}

std::string BusLoadFigures() {
  constexpr int kBoards = 8;
  const protocol::TelemetryRates defaults;
  const BusTiming fd{true, 1e6, 5e6};
  const BusTiming classic{false, 1e6, 1e6};
  char line[200];
  std::snprintf(line, sizeof line, "busload_8x1khz_fd_pct: %.2f %%\n",
                100.0 * ComputeBusLoad(defaults, kBoards, fd).total_fraction);
  std::string out = line;
  std::snprintf(line, sizeof line, "classic_1m_max_telemetry_hz: %.0f Hz\n",
                MaxTelemetryHz(defaults, kBoards, classic, 0.5));
  return out + line;
}

}  // namespace mjc::host
