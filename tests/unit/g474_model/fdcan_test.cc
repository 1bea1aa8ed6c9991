// FDCAN1 against RM0440 §44: init protection, bit rates, filters, RX FIFO indices and
// acknowledge, the TX path, bus-off and its 129 × 11-bit recovery.
#include <gtest/gtest.h>

#include <vector>

#include "mjc/g474model/virtual_chip.h"

namespace {

using namespace mjc::g474model;

constexpr std::uint32_t kCan = 0x40006400, kRam = 0x4000A400;

struct Bench {
  VirtualChip c;
  std::vector<CanBusFrame> sent;
  Bench() {
    c.Write(0x40021058, c.Read(0x40021058, 4) | (1u << 25), 4);  // FDCANEN
    c.Write(0x40021088, 2u << 24, 4);  // FDCANSEL = PCLK1 (16 MHz here)
    c.fdcan1().SetTransmitHook(
        [this](const CanBusFrame& f, Picoseconds) { sent.push_back(f); });
    c.Write(kCan + 0x18, 1u, 4);                               // INIT (already)
    c.Write(kCan + 0x18, 1u | 2u, 4);                          // CCE
    c.Write(kCan + 0x18, 1u | 2u | (1u << 8) | (1u << 9), 4);  // FDOE, BRSE
    // 16 MHz: nominal 1 + 11 + 4 = 16 tq → 1 Mbit/s; data /1, 1 + 1 + 1 = 3 → 5.33.
    c.Write(kCan + 0x1C, (3u << 25) | (0u << 16) | (10u << 8) | 3u, 4);
    c.Write(kCan + 0x0C, (0u << 16) | (0u << 8) | (0u << 4) | 0u, 4);
  }
  void Start() {
    c.Write(kCan + 0x18, c.Read(kCan + 0x18, 4) & ~3u, 4);
    c.AdvanceTo(c.now() + Microseconds(20));
  }
};

TEST(G474Fdcan, ProtectedRegistersNeedInitAndCce) {
  Bench b;
  EXPECT_NEAR(b.c.fdcan1().nominal_bitrate(), 1e6, 1);
  b.Start();
  b.c.Write(kCan + 0x1C, 0, 4);  // NBTP while running
  EXPECT_TRUE(b.c.violations().Contains("FDCAN1", "NBTP"));
  EXPECT_NEAR(b.c.fdcan1().nominal_bitrate(), 1e6, 1);
  EXPECT_EQ(b.c.Read(kCan + 0x18, 4) & 2u, 0u) << "clearing INIT clears CCE";
}

TEST(G474Fdcan, BitRatesFromTheKernelClock) {
  Bench b;
  // At 80 MHz PCLK1 would give 1M/5M with these values; at 16 MHz: NBRP 0, 16 tq.
  b.c.Write(kCan + 0x0C, (0u << 16) | (0u << 8) | (1u << 4) | 0u, 4);  // 1+1+2 tq
  EXPECT_NEAR(b.c.fdcan1().data_bitrate(), 4e6, 1);
  EXPECT_NEAR(b.c.fdcan1().nominal_sample_point(), 12.0 / 16, 1e-9);
}

TEST(G474Fdcan, FiltersFifoIndicesAndAcknowledge) {
  Bench b;
  // Standard filter 0: classic id/mask 0x120/0x7F0 → FIFO1; non-matching → FIFO0.
  b.c.Write(kRam + 0x000, (2u << 30) | (2u << 27) | (0x120u << 16) | 0x7F0u, 4);
  b.c.Write(kCan + 0x80, (1u << 16), 4);  // LSS = 1, ANFS = 0
  b.Start();
  CanBusFrame f;
  f.id = 0x123;
  f.dlc = 2;
  f.data[0] = 0xAB;
  EXPECT_TRUE(b.c.DeliverCanFrame(f));
  EXPECT_EQ(b.c.Read(kCan + 0x98, 4) & 0xFu, 1u);  // FIFO1 fill 1
  for (std::uint32_t id : {0x200u, 0x201u, 0x202u, 0x203u}) {
    f.id = id;
    b.c.DeliverCanFrame(f);
  }
  const std::uint32_t s = b.c.Read(kCan + 0x90, 4);
  EXPECT_EQ(s & 0xFu, 3u);       // full at 3
  EXPECT_TRUE(s & (1u << 24));   // F0F
  EXPECT_TRUE(s & (1u << 25));   // message lost (blocking mode)
  EXPECT_EQ((s >> 8) & 3u, 0u);  // get index
  // Element 0 holds id 0x200 (bits 28:18) and DLC 2.
  EXPECT_EQ((b.c.Read(kRam + 0x0B0, 4) >> 18) & 0x7FFu, 0x200u);
  EXPECT_EQ((b.c.Read(kRam + 0x0B4, 4) >> 16) & 0xFu, 2u);
  b.c.Write(kCan + 0x94, 1, 4);  // acknowledge elements 0 and 1
  const std::uint32_t s2 = b.c.Read(kCan + 0x90, 4);
  EXPECT_EQ(s2 & 0xFu, 1u);
  EXPECT_EQ((s2 >> 8) & 3u, 2u);
}

TEST(G474Fdcan, TransmitThroughTheFifo) {
  Bench b;
  b.Start();
  EXPECT_EQ(b.c.Read(kCan + 0xC4, 4) & 7u, 3u);  // 3 free
  const std::uint32_t put = (b.c.Read(kCan + 0xC4, 4) >> 16) & 3u;
  const std::uint32_t e = kRam + 0x278 + put * 72;
  b.c.Write(e, 0x321u << 18, 4);
  b.c.Write(e + 4, (1u << 21) | (1u << 20) | (9u << 16), 4);  // FD, BRS, DLC 9 → 12 B
  b.c.Write(e + 8, 0x04030201u, 4);
  b.c.Write(kCan + 0xCC, 1u << put, 4);
  EXPECT_EQ(b.c.Read(kCan + 0xC4, 4) & 7u, 2u);
  b.c.AdvanceTo(b.c.now() + Microseconds(200));
  ASSERT_EQ(b.sent.size(), 1u);
  EXPECT_EQ(b.sent[0].id, 0x321u);
  EXPECT_TRUE(b.sent[0].fd && b.sent[0].brs);
  EXPECT_EQ(b.sent[0].length, 12u);
  EXPECT_EQ(b.sent[0].data[2], 3u);
  EXPECT_EQ(b.c.Read(kCan + 0xD4, 4), 1u << put);  // TXBTO
  EXPECT_EQ(b.c.Read(kCan + 0xC4, 4) & 7u, 3u);
}

TEST(G474Fdcan, BusOffRecoveryTakes129Times11Bits) {
  Bench b;
  b.Start();
  b.c.fdcan1().InjectBusOff();
  EXPECT_TRUE(b.c.Read(kCan + 0x44, 4) & (1u << 7));
  EXPECT_TRUE(b.c.Read(kCan + 0x50, 4) & (1u << 19));
  EXPECT_TRUE(b.c.Read(kCan + 0x18, 4) & 1u);  // INIT set by the controller
  b.c.AdvanceTo(b.c.now() + Microseconds(5000));
  EXPECT_TRUE(b.c.fdcan1().bus_off()) << "no recovery while INIT stays set";
  b.c.Write(kCan + 0x18, b.c.Read(kCan + 0x18, 4) & ~1u, 4);
  const Picoseconds t0 = b.c.now();
  while (b.c.Read(kCan + 0x44, 4) & (1u << 7)) {
  }
  EXPECT_NEAR(static_cast<double>(b.c.now() - t0) * 1e-12, 129 * 11 * 1e-6, 2e-6);
}

}  // namespace
