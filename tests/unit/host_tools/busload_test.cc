// Bus-load arithmetic against known worst cases (classical CAN: 135 bits for 8 data
// bytes and 55 for none, the standard stuffing bound) and the CAN FD frame format.
#include "mjc/host/busload.h"

#include <gtest/gtest.h>

namespace {

using namespace mjc;
using host::BusTiming;
using host::FrameTimeS;

TEST(BusLoad, ClassicalWorstCaseMatchesTheStandardBound) {
  const BusTiming classic{false, 1e6, 1e6};
  EXPECT_NEAR(FrameTimeS(8, classic), 135e-6, 1e-12);
  EXPECT_NEAR(FrameTimeS(0, classic), 55e-6, 1e-12);
  EXPECT_NEAR(FrameTimeS(1, classic), 65e-6, 1e-12);  // 47 + 8 + ⌊41/4⌋
}

TEST(BusLoad, FdFrameFollowsTheFormat) {
  const BusTiming fd{true, 1e6, 5e6};
  // 8 bytes: 34 nominal bits; data 69 + 18 stuff + 4 + 17 CRC + 6 fixed = 114.
  EXPECT_NEAR(FrameTimeS(8, fd), 34e-6 + 114 / 5e6, 1e-12);
  // Above 16 bytes the CRC is 21 bits with one more fixed stuff bit.
  const double step16 = FrameTimeS(20, fd) - FrameTimeS(16, fd);
  EXPECT_NEAR(step16, (32 + 8 + 4 + 1) / 5e6, 1e-12);
  // Bit-rate switching pays: the same 8 bytes take under half the classical time.
  EXPECT_LT(FrameTimeS(8, fd), 0.5 * FrameTimeS(8, BusTiming{false, 1e6, 1e6}));
}

TEST(BusLoad, DefaultRatesFitTheBudgetOnFdNotOnClassical) {
  const protocol::TelemetryRates defaults;
  const auto fd = host::ComputeBusLoad(defaults, 8, BusTiming{true, 1e6, 5e6});
  const auto classic = host::ComputeBusLoad(defaults, 8, BusTiming{false, 1e6, 1e6});
  EXPECT_LE(fd.total_fraction, 0.5);
  EXPECT_GT(classic.total_fraction, 1.0);  // 8 boards × 1 kHz do not fit 1 Mbit/s
}

TEST(BusLoad, HighestClassicalTelemetryRateByHand) {
  // Classical CAN at 1 Mbit/s, 8 boards, worst-case stuffing: an 8-byte frame is
  // 135 bits = 135 µs, the 3-byte host heartbeat 47 + 24 + ⌊57/4⌋ = 85 µs, the 7-byte
  // WindowStart 47 + 56 + ⌊89/4⌋ = 125 µs. Besides the angles, each board sends torque,
  // power, energy, control, heartbeat and BoardInfo at 10 Hz and seven 8-byte window
  // frames at 4 windows/s, 88 frames/s: 88 × 135 µs = 11.88 ms/s; a WindowStart per
  // window, 4 × 125 µs = 0.5 ms/s; the host's heartbeat to it adds 10 × 85 µs =
  // 0.85 ms/s. Eight boards: 105.84 ms/s, a load of 0.10584. The 50 % budget leaves
  // 0.39416 for angle frames of 8 × 135 µs each: 0.39416 / 1.08e-3 = 364.963 Hz.
  const double hz = host::MaxTelemetryHz(protocol::TelemetryRates{}, 8,
                                         BusTiming{false, 1e6, 1e6}, 0.5);
  EXPECT_NEAR(hz, 0.39416 / 1.08e-3, 1e-9);
}

// The batched layout by hand. A 48-byte CAN FD frame with bit-rate switching, fields
// of ISO 11898-1: at 1 Mbit/s SOF, 11 identifier bits, RRS, IDE, FDF, res, BRS (17) with
// at most 4 stuff bits, and CRC delimiter, ACK slot and delimiter, EOF (7) and the
// 3-bit intermission (13): 34 µs. At 5 Mbit/s ESI, 4 DLC bits and 384 data bits (389)
// with at most ⌈389/4⌉ = 98 dynamic stuff bits, the 4-bit stuff count, a 21-bit CRC
// (above 16 bytes) and its 7 fixed stuff bits (one before the stuff count, one every
// 4 bits after: 1 + 24/4): 519 bits, 103.8 µs. 137.8 µs a frame.
TEST(BusLoad, FortyEightByteFdFrameByHand) {
  EXPECT_NEAR(FrameTimeS(48, BusTiming{true, 1e6, 5e6}), 137.8e-6, 1e-12);
}

TEST(BusLoad, EightBoardsBatchedAtOneKilohertzByHand) {
  // Eight boards, 1 kHz angles five to a 48-byte frame: 8 × 200 × 137.8 µs = 0.22048.
  // The rest on FD 1/5 Mbit/s: an 8-byte frame is 34 µs + (69 + 18 + 4 + 17 + 6) bits
  // at 5 Mbit/s = 56.8 µs, a 7-byte WindowStart 34 µs + (61 + 16 + 27) / 5 = 54.8 µs,
  // the 3-byte host heartbeat 34 µs + (29 + 8 + 27) / 5 = 46.8 µs. A board's 88 8-byte
  // frames/s (as in the classical case above) take 4.9984 ms/s, its WindowStarts
  // 0.2192 ms/s, its host heartbeats 0.468 ms/s: 5.6856 ms/s, 0.0454848 for eight.
  const protocol::TelemetryRates defaults;
  const BusTiming fd{true, 1e6, 5e6};
  const auto batched = host::ComputeBusLoad(defaults, 8, fd);
  EXPECT_NEAR(batched.total_fraction, 0.22048 + 0.0454848, 1e-9);
  EXPECT_LE(batched.total_fraction, 0.30);
  ASSERT_FALSE(batched.lines.empty());
  EXPECT_EQ(batched.lines.front().message, "TelemetryAngleBatch");
  EXPECT_EQ(batched.lines.front().payload_bytes, 48);
  EXPECT_NEAR(batched.lines.front().hz_per_board, 200.0, 1e-12);
  // One sample a frame on the same bus, the classical layout: 8 × 1000 × 56.8 µs more.
  const auto single = host::ComputeBusLoad(defaults, 8, fd, host::AngleLayout::kSingle);
  EXPECT_NEAR(single.total_fraction, 0.4544 + 0.0454848, 1e-9);
  // Classical CAN keeps one sample a frame.
  const auto classic = host::ComputeBusLoad(defaults, 8, BusTiming{false, 1e6, 1e6});
  EXPECT_EQ(classic.lines.front().message, "TelemetryAngles");
  // The FD rate that fills half the bus: (0.5 − 0.0454848) / (8 × 137.8 µs / 5).
  EXPECT_NEAR(host::MaxTelemetryHz(defaults, 8, fd, 0.5),
              (0.5 - 0.0454848) / (8 * 137.8e-6 / 5), 1e-6);
}

TEST(BusLoad, BenchFiguresAreTheHandComputedLoads) {
  // The two cases worked by hand above, as ./bench prints them: 0.2659648 of FD
  // 1/5 Mbit/s, and 364.963 Hz within half of classical 1 Mbit/s.
  EXPECT_EQ(host::BusLoadFigures(),
            "busload_8x1khz_fd_pct: 26.60 %\n"
            "classic_1m_max_telemetry_hz: 365 Hz\n");
}

}  // namespace
