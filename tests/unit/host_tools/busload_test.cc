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
  // 135 bits = 135 µs, the 3-byte host heartbeat 47 + 24 + ⌊57/4⌋ = 85 µs, the 5-byte
  // WindowStart 47 + 40 + ⌊73/4⌋ = 105 µs. Besides the angles, each board sends torque,
  // power, energy, control, heartbeat and BoardInfo at 10 Hz and seven 8-byte window
  // frames at 4 windows/s, 88 frames/s: 88 × 135 µs = 11.88 ms/s; a WindowStart per
  // window, 4 × 105 µs = 0.42 ms/s; the host's heartbeat to it adds 10 × 85 µs =
  // 0.85 ms/s. Eight boards: 105.2 ms/s, a load of 0.1052. The 50 % budget leaves
  // 0.3948 for angle frames of 8 × 135 µs each: 0.3948 / 1.08e-3 = 365.556 Hz.
  const double hz = host::MaxTelemetryHz(protocol::TelemetryRates{}, 8,
                                         BusTiming{false, 1e6, 1e6}, 0.5);
  EXPECT_NEAR(hz, 0.3948 / 1.08e-3, 1e-9);
}

}  // namespace
