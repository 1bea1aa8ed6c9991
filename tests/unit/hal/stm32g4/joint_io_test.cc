// The tick's drivers against RM0440: TIM1's PWM set-up and compare values, TIM3's
// encoder mode and count, SPI1's frames to the AS5047P, and one whole tick through
// Stm32g4JointIo.
#include "hal/stm32g4/joint_io.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "scripted_space.h"

namespace mjc::stm32g4 {
namespace {

using testing::Equals;
using testing::HasBits;
using testing::ScriptedSpace;

// RM0440 §28.6 (TIM1 at 0x4001_2C00), §29.5 (TIM3 at 0x4000_0400), §39.6 (SPI1 at
// 0x4001_3000), §9.4 (GPIOA at 0x4800_0000, GPIOB 0x4800_0400; BSRR at +0x18).
constexpr Address kTim1 = 0x40012C00, kTim3 = 0x40000400, kSpi1 = 0x40013000;
constexpr Address kGpioaBsrr = 0x48000018, kGpiobBsrr = 0x48000418;

constexpr JointIoBlocks kBlocks{.joint_cs = At(Pin{Port::kA, 4}),
                                .bridge_enable = At(Pin{Port::kB, 12}),
                                .bridge_low_side_min_ns = 1000};
using Io = Stm32g4JointIo<kBlocks>;
static_assert(hal::JointIo<Io>);

TEST(Stm32g4BridgePwm, ComparesMatchAnIndependentComputation) {
  // Leg A high for (1 + d)/2 of ARR = 4250 counts, rounded half up; leg B the rest; no
  // margin: the whole range.
  for (int raw : {-32768, -32767, -16384, -1, 0, 1, 1000, 16384, 32767}) {
    const Duty d = Duty::FromRaw(static_cast<std::int16_t>(raw));
    const double exact = 4250.0 * (1.0 + raw / 32768.0) / 2.0;
    const BridgeCompare c = CompareForDuty(d, 0);
    EXPECT_EQ(c.leg_a, static_cast<std::uint16_t>(std::floor(exact + 0.5))) << raw;
    EXPECT_EQ(c.leg_a + c.leg_b, 4250) << raw;
  }
  EXPECT_EQ(CompareForDuty(Duty::FromRaw(0), 0).leg_a, 2125);
  EXPECT_EQ(CompareForDuty(Duty::FromRaw(16384), 0).leg_a, 3188);  // 3187.5 rounds up
  EXPECT_EQ(CompareForDuty(Duty::FromRaw(-32768), 0).leg_a, 0);
  EXPECT_EQ(CompareForDuty(Duty::FromRaw(32767), 0).leg_a, 4250);
  // Every raw value: within half a count of (1 + d)/2 × ARR, and symmetric.
  for (int raw = -32768; raw <= 32767; ++raw) {
    const BridgeCompare c =
        CompareForDuty(Duty::FromRaw(static_cast<std::int16_t>(raw)), 0);
    ASSERT_LE(std::abs(c.leg_a - 4250.0 * (1.0 + raw / 32768.0) / 2.0), 0.5) << raw;
  }
}

TEST(Stm32g4BridgePwm, MarginKeepsEachLowSideOnItsMinimum) {
  // Centre-aligned PWM mode 1: OCxREF is low for 2 × (ARR − CCR) counts a period, the
  // low side on for that less one dead time (43 counts at 170 MHz). The margin for
  // 1 µs, computed here in double: ⌈(1 µs + 43 / 170 MHz) × 170 MHz / 2⌉ = 107.
  const double f = 170e6, dead = 43 / f;
  const auto n = static_cast<std::uint32_t>(std::ceil((1e-6 + dead) * f / 2));
  EXPECT_EQ(n, 107u);
  static_assert(CompareMargin(1000) == 107);
  EXPECT_GE(2 * n / f - dead, 1e-6);
  EXPECT_LT(2 * (n - 1) / f - dead, 1e-6) << "the smallest margin that does it";
  for (int raw = -32768; raw <= 32767; ++raw) {
    const BridgeCompare c =
        CompareForDuty(Duty::FromRaw(static_cast<std::int16_t>(raw)), n);
    const double exact = std::floor(4250.0 * (1.0 + raw / 32768.0) / 2.0 + 0.5);
    ASSERT_EQ(c.leg_a, std::clamp(exact, double(n), 4250.0 - n)) << raw;
    ASSERT_EQ(c.leg_a + c.leg_b, 4250) << raw;
    ASSERT_GE(2 * (4250 - c.leg_a) / f - dead, 1e-6) << raw;  // leg A's low side
    ASSERT_GE(2 * (4250 - c.leg_b) / f - dead, 1e-6) << raw;  // leg B's low side
  }
  // What it costs: the largest mean voltage, (CCR1 − CCR2) / ARR at a full command.
  const BridgeCompare full = CompareForDuty(Duty::FromRaw(32767), n);
  EXPECT_NEAR((full.leg_a - full.leg_b) / 4250.0, 1 - 2 * 107 / 4250.0, 1e-12);
}

TEST(Stm32g4BridgePwm, DeadTimeEncoding) {
  // RM0440 TIMx_BDTR.DTG at tDTS = 1/170 MHz: 0xxxxxxx → DTG × tDTS.
  static_assert(kDeadTimeCode == 43);  // 252.9 ns ≥ 250 ns
  static_assert(DeadTimeCode(1000, 170'000'000) == (0x80 | (85 - 64)));  // 170 ticks
  static_assert(DeadTimeCode(2000, 170'000'000) == (0xC0 | (43 - 32)));  // 340 ticks
  static_assert(DeadTimePs(0x80 | 21, 170'000'000) >= 1'000'000);
}

TEST(Stm32g4BridgePwm, InitSequence) {
  ScriptedSpace s;
  Stm32g4BridgePwm<kTim1, 107>::Init();
  EXPECT_EQ(s.Peek(kTim1 + 0x2C), 4250u);  // ARR: 170 MHz / (2 × 20 kHz)
  EXPECT_EQ(s.Peek(kTim1 + 0x30), 3u);     // RCR: update every 4 half-periods
  EXPECT_EQ(s.Peek(kTim1 + 0x28), 0u);     // PSC
  // CCMR1: OC1M = OC2M = 0110 (PWM mode 1) at 6:4 / 14:12, OC1PE (3), OC2PE (11).
  EXPECT_EQ(s.Peek(kTim1 + 0x18), 0x6868u);
  EXPECT_EQ(s.Peek(kTim1 + 0x34), 0u);      // CCR1: low side on
  EXPECT_EQ(s.Peek(kTim1 + 0x38), 0u);      // CCR2
  EXPECT_EQ(s.Peek(kTim1 + 0x04), 0xA00u);  // CR2: OIS1N (9), OIS2N (11)
  EXPECT_EQ(s.Peek(kTim1 + 0x20), 0x55u);   // CCER: CC1E, CC1NE, CC2E, CC2NE
  // BDTR: DTG 43, LOCK 01 (9:8), OSSI (10), OSSR (11), then MOE (15).
  EXPECT_EQ(s.WritesTo(kTim1 + 0x44), (std::vector<std::uint32_t>{0x0D2Bu, 0x8D2Bu}));
  EXPECT_EQ(s.Peek(kTim1 + 0x0C), 1u);  // DIER.UIE
  // CR1: CMS = 01 (6:5), ARPE (7), URS (2), CEN (0) last, after MOE.
  EXPECT_EQ(s.Peek(kTim1 + 0x00), 0xA5u);
  const long moe = s.FirstWrite(kTim1 + 0x44, HasBits(1u << 15));
  const long cen = s.FirstWrite(kTim1 + 0x00, HasBits(1u));
  const long ug = s.FirstWrite(kTim1 + 0x14, Equals(1u));
  ASSERT_GE(ug, 0);
  EXPECT_LT(ug, moe);
  EXPECT_LT(moe, cen);
  // The compare values are set before the outputs are enabled.
  EXPECT_LT(s.FirstWrite(kTim1 + 0x34, testing::Any()),
            s.FirstWrite(kTim1 + 0x20, testing::Any()));
}

TEST(Stm32g4QuadratureEncoder, X4ModeAndCount) {
  ScriptedSpace s;
  Stm32g4QuadratureEncoder<kTim3>::Init();
  EXPECT_EQ(s.Peek(kTim3 + 0x08), 0b0011u);  // SMCR.SMS = 0011, SMS[3] (bit 16) = 0
  // CCMR1: CC1S = CC2S = 01, IC1F = IC2F = 0110.
  EXPECT_EQ(s.Peek(kTim3 + 0x18), 0x6161u);
  EXPECT_EQ(s.Peek(kTim3 + 0x2C), 0xFFFFu);
  EXPECT_EQ(s.Peek(kTim3 + 0x20), 0u);
  EXPECT_EQ(s.Peek(kTim3 + 0x00), 1u);   // CEN
  s.memory[kTim3 + 0x24] = 0x8000ABCDu;  // CNT with UIFCPY set: only 15:0 are the count
  EXPECT_EQ(Stm32g4QuadratureEncoder<kTim3>::ISR_Count(), 0xABCD);
}

// SPI1 answers as the manual says: a frame written to DR is received 16 clocks later
// (here: at once), RXNE set and BSY clear, DR returns the sensor's word.
void ModelSpi(ScriptedSpace& s, std::uint16_t answer) {
  s.on_read = [&s, answer](Address a) -> std::optional<std::uint32_t> {
    if (a == kSpi1 + 0x08) {
      return s.memory.count(kSpi1 + 0x0C) != 0 ? std::optional<std::uint32_t>(1u)
                                               : std::optional<std::uint32_t>(2u);
    }
    if (a == kSpi1 + 0x0C) {
      s.memory.erase(kSpi1 + 0x0C);
      return answer;
    }
    return std::nullopt;
  };
}

TEST(As5047p, InitConfiguresMode1And16BitFrames) {
  ScriptedSpace s;
  ModelSpi(s, 0x1234);
  As5047p<kSpi1, At(Pin{Port::kA, 4})> sensor;
  EXPECT_TRUE(sensor.Init());
  // CR1: CPHA (0), MSTR (2), BR = 100 (/32, 5:3), SSI (8), SSM (9); then SPE (6).
  EXPECT_EQ(s.WritesTo(kSpi1 + 0x00), (std::vector<std::uint32_t>{0u, 0x325u, 0x365u}));
  EXPECT_EQ(s.Peek(kSpi1 + 0x04), 0xF00u);  // CR2: DS = 1111, FRXTH = 0
  // The primer: CS low (BR4), the read-ANGLECOM command as a 16-bit write, CS high (BS4).
  const long cs_low = s.FirstWrite(kGpioaBsrr, Equals(1u << 20));
  const long command = s.FirstWrite(kSpi1 + 0x0C, Equals(0xFFFF));
  ASSERT_GE(cs_low, 0);
  ASSERT_GE(command, 0);
  EXPECT_LT(cs_low, command);
  EXPECT_EQ(s.log[static_cast<std::size_t>(command)].bytes, 2u);
  EXPECT_GE(s.FirstWrite(kGpioaBsrr, Equals(1u << 4), command), 0);
}

TEST(Stm32g4JointIo, OneTick) {
  ScriptedSpace s;
  ModelSpi(s, 0xC2D5);
  Io io;
  ASSERT_TRUE(io.Init());
  s.memory[kTim3 + 0x24] = 0x0102;
  s.log.clear();

  io.ISR_BeginTick();
  const Sample sample = io.ISR_Read();
  EXPECT_EQ(sample.motor_count, 0x0102);
  EXPECT_EQ(sample.joint_frame, 0xC2D5);
  EXPECT_FALSE(sample.tick_overrun);
  // The frame is read before CS rises.
  const long dr_read = [&] {
    for (std::size_t i = 0; i < s.log.size(); ++i) {
      if (!s.log[i].write && s.log[i].address == kSpi1 + 0x0C)
        return static_cast<long>(i);
    }
    return -1L;
  }();
  ASSERT_GE(dr_read, 0);
  EXPECT_GT(s.FirstWrite(kGpioaBsrr, Equals(1u << 4)), dr_read);

  Actuation a;
  a.bridge_enabled = true;
  a.duty = Duty::FromRaw(-16384);  // −0.5: leg A 1062.5 → 1063, leg B 3187
  io.ISR_Write(a);
  EXPECT_EQ(s.Peek(kTim1 + 0x34), 1063u);
  EXPECT_EQ(s.Peek(kTim1 + 0x38), 3187u);
  EXPECT_EQ(s.Peek(kGpiobBsrr), 1u << 12);  // enable high
  // The next frame: CS low, then the command.
  const long cs_low = s.FirstWrite(kGpioaBsrr, Equals(1u << 20));
  EXPECT_LT(cs_low, s.FirstWrite(kSpi1 + 0x0C, Equals(0xFFFF)));

  // Disabled: enable low first, then both low sides on.
  s.log.clear();
  io.ISR_BeginTick();
  (void)io.ISR_Read();
  io.ISR_Write(Actuation{});
  const long enable_low = s.FirstWrite(kGpiobBsrr, Equals(1u << 28));
  ASSERT_GE(enable_low, 0);
  EXPECT_LT(enable_low, s.FirstWrite(kTim1 + 0x34, Equals(0)));
  EXPECT_EQ(s.Peek(kTim1 + 0x38), 0u);
}

TEST(Stm32g4JointIo, AnOverrunIsReportedOnTheNextTick) {
  ScriptedSpace s;
  ModelSpi(s, 0);
  Io io;
  ASSERT_TRUE(io.Init());
  io.ISR_BeginTick();
  (void)io.ISR_Read();
  s.cycles += 17'001;  // the tick's work took longer than 100 µs
  io.ISR_Write(Actuation{});
  EXPECT_EQ(io.overruns(), 1u);
  io.ISR_BeginTick();
  EXPECT_TRUE(io.ISR_Read().tick_overrun);
  io.ISR_Write(Actuation{});
  io.ISR_BeginTick();
  EXPECT_FALSE(io.ISR_Read().tick_overrun);
  EXPECT_GT(io.max_tick_cycles(), 17'000u);
}

TEST(Stm32g4JointIo, AMissingFrameFailsParity) {
  ScriptedSpace s;
  ModelSpi(s, 0x1234);
  Io io;
  ASSERT_TRUE(io.Init());
  s.on_read = [](Address a) -> std::optional<std::uint32_t> {
    if (a == kSpi1 + 0x08) return 0x80u;  // BSY, no RXNE
    return std::nullopt;
  };
  io.ISR_BeginTick();
  EXPECT_EQ(io.ISR_Read().joint_frame, 0x8000);
}

TEST(Stm32g4JointIo, EmergencyStopClearsMoe) {
  ScriptedSpace s;
  s.memory[kTim1 + 0x44] = 0x8D2B;
  Io::EmergencyStop();
  EXPECT_EQ(s.Peek(kGpiobBsrr), 1u << 28);
  EXPECT_EQ(s.Peek(kTim1 + 0x44), 0x0D2Bu);
}

}  // namespace
}  // namespace mjc::stm32g4
