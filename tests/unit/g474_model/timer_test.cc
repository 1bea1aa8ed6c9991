// TIM1/TIM3 against RM0440's timer chapters: update rate for PSC/ARR/RCR/CMS, PWM duty,
// dead time, encoder counting and wrap in each mode through the AF routing.
#include <gtest/gtest.h>

#include "mjc/g474model/virtual_chip.h"

namespace {

using namespace mjc::g474model;

constexpr std::uint32_t kT1 = 0x40012C00, kT3 = 0x40000400;

VirtualChip& WithTimers(VirtualChip& c) {
  c.Write(0x40021060, 1u << 11, 4);                    // TIM1EN
  c.Write(0x40021058, c.Read(0x40021058, 4) | 2u, 4);  // TIM3EN
  c.Write(0x4002104C, 0x3u, 4);                        // GPIOA, GPIOB
  return c;
}

// Counts update interrupts over `seconds` of virtual time.
int CountUpdates(VirtualChip& c, double seconds) {
  int n = 0;
  c.SetHandler(irq::kTim1Up, [&] {
    ++n;
    c.Write(kT1 + 0x10, 0, 4);  // clear UIF
  });
  c.Write(0xE000E100, 1u << irq::kTim1Up, 4);
  c.Write(kT1 + 0x0C, 1, 4);  // UIE
  c.AdvanceTo(c.now() + static_cast<Picoseconds>(seconds * 1e12));
  // The handler counts into this frame: disabled and replaced before the frame goes.
  c.Write(0xE000E180, 1u << irq::kTim1Up, 4);  // ICER
  c.SetHandler(irq::kTim1Up, [] {});
  return n;
}

TEST(G474Timer, EdgeAlignedUpdateRate) {
  VirtualChip c;  // 16 MHz HSI16: TIM1 kernel clock 16 MHz
  WithTimers(c);
  c.Write(kT1 + 0x28, 15, 4);   // PSC → 1 MHz
  c.Write(kT1 + 0x2C, 999, 4);  // ARR → 1 kHz
  c.Write(kT1 + 0x14, 1, 4);    // UG
  c.Write(kT1 + 0x10, 0, 4);
  c.Write(kT1 + 0x00, 1, 4);  // CEN
  EXPECT_NEAR(CountUpdates(c, 0.1), 100, 1);
}

TEST(G474Timer, CentreAlignedWithRepetitionCounter) {
  VirtualChip c;
  WithTimers(c);
  c.Write(kT1 + 0x2C, 800, 4);  // 16 MHz / (2·800) = 10 kHz PWM
  c.Write(kT1 + 0x30, 0, 4);    // RCR 0: updates at both ends → 20 kHz
  c.Write(kT1 + 0x14, 1, 4);
  c.Write(kT1 + 0x10, 0, 4);
  c.Write(kT1 + 0x00, 1u | (1u << 5), 4);  // CMS = 01, CEN
  EXPECT_NEAR(CountUpdates(c, 0.01), 200, 1);
  c.Write(kT1 + 0x30, 1, 4);  // RCR 1: once per period
  c.Write(kT1 + 0x14, 1, 4);
  c.Write(kT1 + 0x10, 0, 4);
  EXPECT_NEAR(CountUpdates(c, 0.01), 100, 1);
}

TEST(G474Timer, ComplementaryPwmWithDeadTime) {
  VirtualChip c;
  WithTimers(c);
  c.Write(kT1 + 0x2C, 799, 4);                    // 20 kHz edge-aligned at 16 MHz
  c.Write(kT1 + 0x18, (6u << 4) | (1u << 3), 4);  // CH1 PWM mode 1, preload
  c.Write(kT1 + 0x34, 200, 4);                    // 25 %
  c.Write(kT1 + 0x20, 1u | (1u << 2), 4);         // CC1E, CC1NE
  c.Write(kT1 + 0x44, 16u, 4);                    // DTG 16 → 1 µs at 16 MHz, MOE off
  c.Write(kT1 + 0x14, 1, 4);
  c.Write(kT1 + 0x00, 1, 4);
  EXPECT_FALSE(c.tim1().Wave(1, false).driven) << "MOE = 0, OSSI = 0: Hi-Z";
  c.Write(kT1 + 0x44, 16u | (1u << 15), 4);  // MOE
  const OutputWave high = c.tim1().Wave(1, false), low = c.tim1().Wave(1, true);
  // 50 µs period: 1 µs dead time = 0.02 of it off each output's active phase.
  EXPECT_NEAR(high.duty, 0.25 - 0.02, 1e-9);
  EXPECT_NEAR(low.duty, 0.75 - 0.02, 1e-9);
  // Through the pins: PA8 AF6 (CH1), PA7 AF6 (CH1N), PB0 enable.
  c.Write(0x48000000,
          (c.Read(0x48000000, 4) & ~((3u << 16) | (3u << 14))) | (2u << 16) | (2u << 14),
          4);
  c.Write(0x48000020, 6u << 28, 4);
  c.Write(0x48000024, 6u, 4);
  c.Write(0x48000400, (c.Read(0x48000400, 4) & ~3u) | 1u, 4);
  c.Write(0x48000418, 1u, 4);
  const BridgeDrive d = c.HBridge(Pin('A', 8), Pin('A', 7), Pin('B', 0));
  EXPECT_TRUE(d.enabled);
  EXPECT_NEAR(d.duty, 0.23 - 0.73, 1e-9);
  // A wrong AF number on PA8 and the bridge input floats.
  c.Write(0x48000024, 5u, 4);
  EXPECT_TRUE(c.HBridge(Pin('A', 8), Pin('A', 7), Pin('B', 0)).floating);
}

// TIM3 encoder on PA6 (CH1, AF2) and PA4 (CH2, AF2).
void SetUpEncoder(VirtualChip& c, unsigned sms, std::uint32_t arr) {
  WithTimers(c);
  c.AttachEncoder(Pin('A', 6), Pin('A', 4));
  c.Write(0x48000000,
          (c.Read(0x48000000, 4) & ~((3u << 12) | (3u << 8))) | (2u << 12) | (2u << 8),
          4);
  c.Write(0x48000020, (2u << 24) | (2u << 16), 4);
  c.Write(kT3 + 0x18, 1u | (1u << 8), 4);  // CC1S = CC2S = 01
  c.Write(kT3 + 0x08, (sms & 7u) | ((sms >> 3) << 16), 4);
  c.Write(kT3 + 0x2C, arr, 4);
  c.Write(kT3 + 0x00, 1, 4);
}

TEST(G474Timer, EncoderX4CountsEveryEdgeBothWaysAndWrapsAtArr) {
  VirtualChip c;
  SetUpEncoder(c, 3, 999);
  c.MoveEncoder(10);
  EXPECT_EQ(c.Read(kT3 + 0x24, 4), 10u);
  c.MoveEncoder(-5);
  EXPECT_EQ(c.Read(kT3 + 0x24, 4), 995u);   // wrapped below 0 to ARR
  EXPECT_TRUE(c.Read(kT3 + 0x10, 4) & 1u);  // UIF at the underflow
}

TEST(G474Timer, EncoderX2AndX1CountFewerEdges) {
  VirtualChip c2;
  SetUpEncoder(c2, 1, 0xFFFF);
  c2.MoveEncoder(40);
  EXPECT_EQ(c2.Read(kT3 + 0x24, 4), 20u);
  c2.MoveEncoder(0);
  EXPECT_EQ(c2.Read(kT3 + 0x24, 4), 0u);
  VirtualChip c1;
  SetUpEncoder(c1, 14, 0xFFFF);
  c1.MoveEncoder(40);
  EXPECT_EQ(c1.Read(kT3 + 0x24, 4), 10u);
  c1.MoveEncoder(0);
  EXPECT_EQ(c1.Read(kT3 + 0x24, 4), 0u);
}

TEST(G474Timer, EncoderOnAWrongAlternateFunctionDoesNotCount) {
  VirtualChip c;
  SetUpEncoder(c, 3, 0xFFFF);
  c.Write(0x48000020, (5u << 24) | (5u << 16), 4);  // AF5 = SPI1 on PA6/PA4
  c.MoveEncoder(100);
  EXPECT_EQ(c.Read(kT3 + 0x24, 4), 0u);
}

}  // namespace
