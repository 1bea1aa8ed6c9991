// NVIC preemption and priorities, AIRCR's reset request, DWT.CYCCNT, and the address
// decoder's reports (ARMv7-M ARM B3.4, B3.2.6, C1.8).
#include <gtest/gtest.h>

#include <vector>

#include "mjc/g474model/virtual_chip.h"

namespace {

using namespace mjc::g474model;

constexpr std::uint32_t kIser = 0xE000E100, kIspr = 0xE000E200, kIpr = 0xE000E400;

void SetPriority(VirtualChip& c, int irq, std::uint8_t p) {
  const std::uint32_t word = kIpr + static_cast<std::uint32_t>(irq & ~3);
  const unsigned shift = 8u * static_cast<unsigned>(irq & 3);
  c.Write(word, (c.Read(word, 4) & ~(0xFFu << shift)) | (std::uint32_t{p} << shift), 4);
}
void Enable(VirtualChip& c, int irq) {
  c.Write(kIser + 4u * static_cast<std::uint32_t>(irq / 32), 1u << (irq % 32), 4);
}
void Pend(VirtualChip& c, int irq) {
  c.Write(kIspr + 4u * static_cast<std::uint32_t>(irq / 32), 1u << (irq % 32), 4);
}

TEST(G474Nvic, HigherPriorityPreemptsLowerDoesNot) {
  VirtualChip c;
  std::vector<std::string> log;
  SetPriority(c, 40, 0x80);  // low urgency
  SetPriority(c, 41, 0x10);  // high urgency
  SetPriority(c, 42, 0x80);  // same as 40
  c.SetHandler(40, [&] {
    log.push_back("40 in");
    Pend(c, 41);  // preempts
    log.push_back("40 mid");
    Pend(c, 42);  // same level: waits
    log.push_back("40 out");
  });
  c.SetHandler(41, [&] { log.push_back("41"); });
  c.SetHandler(42, [&] { log.push_back("42"); });
  for (int i : {40, 41, 42}) Enable(c, i);
  Pend(c, 40);
  EXPECT_EQ(log, (std::vector<std::string>{"40 in", "41", "40 mid", "40 out", "42"}));
}

TEST(G474Nvic, PrimaskHoldsInterruptsUntilCleared) {
  VirtualChip c;
  int taken = 0;
  c.SetHandler(40, [&] { ++taken; });
  Enable(c, 40);
  c.MaskInterrupts(true);
  Pend(c, 40);
  EXPECT_EQ(taken, 0);
  c.MaskInterrupts(false);
  EXPECT_EQ(taken, 1);
}

TEST(G474Scb, SysResetReqNeedsTheVectKey) {
  VirtualChip c;
  std::optional<ResetCause> cause;
  c.SetResetHandler([&](ResetCause rc) { cause = rc; });
  c.Write(0xE000ED0C, 1u << 2, 4);  // no key
  EXPECT_FALSE(cause);
  c.Write(0xE000ED0C, (0x05FAu << 16) | (1u << 2), 4);
  ASSERT_TRUE(cause);
  EXPECT_EQ(*cause, ResetCause::kSoftware);
  EXPECT_TRUE(c.Read(0x40021094, 4) & csr::kSftrstf);
}

TEST(G474Scb, DefaultResetHandlerUnwindsTheFirmware) {
  VirtualChip c;
  EXPECT_THROW(c.Write(0xE000ED0C, (0x05FAu << 16) | (1u << 2), 4), ChipReset);
}

TEST(G474Dwt, CyccntCountsCpuCyclesOnlyWithTrcena) {
  VirtualChip c;
  c.Write(0xE0001000, 1, 4);  // CYCCNTENA without TRCENA
  EXPECT_TRUE(c.violations().Contains("DWT", "TRCENA"));
  c.Write(0xE000EDFC, 1u << 24, 4);
  c.Write(0xE0001004, 0, 4);
  c.Write(0xE0001000, 1, 4);
  const std::uint32_t a = c.Read(0xE0001004, 4);
  c.SpendCycles(1000);
  const std::uint32_t b = c.Read(0xE0001004, 4);
  EXPECT_EQ(b - a, 1000u + 4u);  // the cycles spent plus one access
}

TEST(G474Bus, UnmappedAddressesAreReported) {
  VirtualChip c;
  EXPECT_EQ(c.Read(0x50000000, 4), 0u);
  EXPECT_TRUE(c.violations().Contains("bus", "0x50000000"));
  c.Write(0x40021000 + 0x3FC, 1, 4);  // RCC reserved offset
  EXPECT_TRUE(c.violations().Contains("bus", "reserved"));
}

TEST(G474Gpio, AlternateFunctionRoutingFollowsTheTable) {
  VirtualChip c;
  c.Write(0x4002104C, 1u, 4);  // GPIOAEN
  // PA8 in AF mode with AF6 carries TIM1_CH1; AF5 carries nothing modelled.
  c.Write(0x48000000, (c.Read(0x48000000, 4) & ~(3u << 16)) | (2u << 16), 4);
  c.Write(0x48000024, 5u, 4);
  EXPECT_EQ(c.pinmux().SignalOn(Pin('A', 8)), Signal::kNone);
  c.Write(0x48000024, 6u, 4);
  EXPECT_EQ(c.pinmux().SignalOn(Pin('A', 8)), Signal::kTim1Ch1);
}

TEST(G474Gpio, BsrrSetWinsAndIdrFollowsThePin) {
  VirtualChip c;
  c.Write(0x4002104C, 2u, 4);                                  // GPIOBEN
  c.Write(0x48000400, (c.Read(0x48000400, 4) & ~3u) | 1u, 4);  // PB0 output
  c.Write(0x48000418, 0x00010001u, 4);                         // set and reset PB0
  EXPECT_EQ(c.Read(0x48000414, 4) & 1u, 1u);
  EXPECT_EQ(c.Read(0x48000410, 4) & 1u, 1u);
  c.Write(0x48000428, 1u, 4);  // BRR
  EXPECT_EQ(c.Read(0x48000410, 4) & 1u, 0u);
}

}  // namespace
