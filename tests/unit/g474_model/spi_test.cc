// SPI1 frame timing and the AS5047P's one-frame latency, parity and CSn timing.
#include <gtest/gtest.h>

#include "mjc/g474model/virtual_chip.h"

namespace {

using namespace mjc::g474model;

constexpr std::uint32_t kSpi = 0x40013000, kGpioA = 0x48000000;

struct Bench {
  VirtualChip c;
  As5047p* dev = nullptr;
  Bench() {
    c.Write(0x40021060, 1u << 12, 4);  // SPI1EN
    c.Write(0x4002104C, 1u, 4);        // GPIOAEN
    dev = &c.AttachAs5047p();
    // PA4 output high (CSn), PA5/6/7 AF5.
    c.Write(kGpioA + 0x18, 1u << 4, 4);
    std::uint32_t m = c.Read(kGpioA, 4) & ~(0xFFu << 8);
    c.Write(kGpioA, m | (1u << 8) | (2u << 10) | (2u << 12) | (2u << 14), 4);
    c.Write(kGpioA + 0x20, (5u << 20) | (5u << 24) | (5u << 28), 4);
    c.Write(kSpi + 0x04, (15u << 8), 4);  // DS 16 bits, FRXTH 0
    // Mode 1, master, BR = /4 (16 MHz → 4 MHz), SSM = SSI = 1, SPE.
    c.Write(kSpi, 1u | (1u << 2) | (1u << 3) | (1u << 8) | (1u << 9) | (1u << 6), 4);
  }
  std::uint16_t Transfer(std::uint16_t word) {
    c.Write(kGpioA + 0x18, 1u << 20, 4);  // CSn low
    c.AdvanceTo(c.now() + Nanoseconds(400));
    c.Write(kSpi + 0x0C, word, 2);
    while (!(c.Read(kSpi + 0x08, 4) & 1u)) {
    }
    const auto r = static_cast<std::uint16_t>(c.Read(kSpi + 0x0C, 2));
    c.Write(kGpioA + 0x18, 1u << 4, 4);  // CSn high
    c.AdvanceTo(c.now() + Nanoseconds(400));
    return r;
  }
};

TEST(G474Spi, SixteenBitFrameTakesSixteenSckPeriods) {
  Bench b;
  b.c.Write(kGpioA + 0x18, 1u << 20, 4);
  b.c.AdvanceTo(b.c.now() + Nanoseconds(400));
  b.c.Write(kSpi + 0x0C, 0xFFFF, 2);
  const Picoseconds t0 = b.c.now();
  while (!(b.c.Read(kSpi + 0x08, 4) & 1u)) {
  }
  EXPECT_NEAR(static_cast<double>(b.c.now() - t0) * 1e-12, 16 / 4e6, 0.3e-6);
}

TEST(G474As5047p, AnswerArrivesInTheNextFrameWithEvenParity) {
  Bench b;
  b.dev->SetAngle(1234);
  const std::uint16_t read_angle = As5047p::Command(As5047p::kAngleCom, true);
  EXPECT_EQ(read_angle, 0xFFFFu);         // the datasheet's ANGLECOM read command
  EXPECT_EQ(b.Transfer(read_angle), 0u);  // first frame: nothing to answer yet
  const std::uint16_t r = b.Transfer(As5047p::Command(As5047p::kNop, true));
  EXPECT_EQ(r & 0x3FFFu, 1234u);
  EXPECT_FALSE(r & 0x4000u);
  EXPECT_FALSE(OddBitCount(r));
  EXPECT_TRUE(b.c.violations().empty()) << b.c.violations().ToString();
}

TEST(G474As5047p, BadParitySetsTheErrorFlagAndErrflReports) {
  Bench b;
  b.Transfer(0x7FFF);  // ANGLECOM read with the parity bit wrong
  const std::uint16_t r = b.Transfer(As5047p::Command(As5047p::kErrfl, true));
  EXPECT_TRUE(r & 0x4000u);  // EF
  const std::uint16_t e = b.Transfer(As5047p::Command(As5047p::kNop, true));
  EXPECT_EQ(e & 0x3FFFu, 4u);     // PARERR
  EXPECT_EQ(b.dev->errfl(), 0u);  // reading cleared it
}

TEST(G474As5047p, CsnHighTooShortIsAViolation) {
  Bench b;
  b.c.Write(kGpioA + 0x18, 1u << 20, 4);
  b.c.Write(kGpioA + 0x18, 1u << 4, 4);
  b.c.Write(kGpioA + 0x18, 1u << 20, 4);  // high for one access: ~250 ns at 16 MHz
  EXPECT_TRUE(b.c.violations().Contains("AS5047P", "t_CSn"));
}

TEST(G474As5047p, WrongSckPinGivesNoAngle) {
  Bench b;
  b.dev->SetAngle(777);
  b.c.Write(kGpioA + 0x20, (5u << 24) | (5u << 28), 4);  // PA5 no longer AF5
  b.Transfer(0xFFFF);
  EXPECT_EQ(b.Transfer(0xFFFF), 0u);
}

}  // namespace
