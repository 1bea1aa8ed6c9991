// FDCAN1's initialisation sequence, filters, bit timing and message-RAM elements
// against RM0440 §44 (FDCAN1 registers at 0x4000_6400, FDCAN_CONFIG at 0x4000_6500,
// message RAM at 0x4000_A400).
#include "hal/stm32g4/fdcan.h"

#include <gtest/gtest.h>

#include <array>

#include "scripted_space.h"

namespace mjc::stm32g4 {
namespace {

using testing::Equals;
using testing::HasBits;
using testing::LacksBits;
using testing::ScriptedSpace;

constexpr Address kCan = 0x40006400;
constexpr Address kCccr = kCan + 0x18, kNbtp = kCan + 0x1C, kDbtp = kCan + 0x0C;
constexpr Address kTdcr = kCan + 0x48, kIr = kCan + 0x50, kIe = kCan + 0x54;
constexpr Address kIls = kCan + 0x58, kIle = kCan + 0x5C, kRxgfc = kCan + 0x80;
constexpr Address kRxf0s = kCan + 0x90, kRxf0a = kCan + 0x94, kTxfqs = kCan + 0xC4;
constexpr Address kTxbar = kCan + 0xCC, kPsr = kCan + 0x44, kEcr = kCan + 0x40;
constexpr Address kCkdiv = 0x40006500;
constexpr Address kRam = 0x4000A400;
constexpr std::uint32_t kInit = 1, kCce = 2;

// CCCR as the manual describes it: INIT reads back as written, CSA follows CSR, CCE is
// writable only with INIT set and cleared with INIT.
void ModelCccr(ScriptedSpace& s) {
  s.memory[kCccr] = kInit;  // after reset the controller is in initialisation
  s.after_write = [&s](Address a, std::uint32_t v) {
    if (a == kCccr) {
      std::uint32_t cccr = v & ~(1u << 3);
      if (v & (1u << 4)) cccr |= 1u << 3;
      if ((v & kInit) == 0) cccr &= ~kCce;
      s.memory[kCccr] = cccr;
    }
  };
}

std::unique_ptr<Stm32g4Fdcan> Started(ScriptedSpace& s) {
  ModelCccr(s);
  auto can = std::make_unique<Stm32g4Fdcan>();
  const std::array<CanFilter, 2> filters{{{0x123, 0x7FF}, {0x010, 0x70F}}};
  EXPECT_EQ(can->Init(filters), FdcanResult::kOk);
  return can;
}

TEST(Stm32g4Fdcan, InitSequenceAndValues) {
  ScriptedSpace s;
  auto can = Started(s);
  const long init = s.FirstWrite(kCccr, HasBits(kInit));
  const long cce = s.FirstWrite(kCccr, HasBits(kInit | kCce));
  const long nbtp = s.FirstWrite(kNbtp, testing::Any());
  const long ckdiv = s.FirstWrite(kCkdiv, Equals(0));
  const long leave = s.FirstWrite(kCccr, LacksBits(kInit), cce);
  for (long i : {init, cce, nbtp, ckdiv, leave}) ASSERT_GE(i, 0);
  EXPECT_LT(init, cce);
  EXPECT_LT(cce, ckdiv);
  EXPECT_LT(cce, nbtp);
  EXPECT_LT(nbtp, leave);
  EXPECT_LT(s.FirstWrite(kRxgfc, testing::Any()), leave);
  // FDOE (8) and BRSE (9) were set while configuring.
  EXPECT_GE(s.FirstWrite(kCccr, HasBits(kInit | kCce | (1u << 8) | (1u << 9))), 0);
  // 1 Mbit/s at 85 MHz: NSJW 17−1 (31:25), NBRP 1−1 (24:16), NTSEG1 67−1 (15:8),
  // NTSEG2 17−1 (6:0): 85 tq, sample point 68/85 = 80 %.
  EXPECT_EQ(s.Peek(kNbtp), (16u << 25) | (66u << 8) | 16u);
  // 5 Mbit/s: TDC (23), DBRP 0, DTSEG1 12−1 (12:8), DTSEG2 4−1 (7:4), DSJW 4−1 (3:0).
  EXPECT_EQ(s.Peek(kDbtp), (1u << 23) | (11u << 8) | (3u << 4) | 3u);
  EXPECT_EQ(s.Peek(kTdcr), 12u << 8);  // TDCO 12 mtq, TDCF 0
  // Filters: SFT = 10 (classic), SFEC = 001 (FIFO 0), SFID1 = id, SFID2 = mask.
  EXPECT_EQ(s.Peek(kRam + 0), 0x80000000u | 0x08000000u | (0x123u << 16) | 0x7FFu);
  EXPECT_EQ(s.Peek(kRam + 4), 0x80000000u | 0x08000000u | (0x010u << 16) | 0x70Fu);
  // RXGFC: LSS = 2, ANFS = ANFE = 10 (reject), RRFS, RRFE.
  EXPECT_EQ(s.Peek(kRxgfc), (2u << 16) | (2u << 4) | (2u << 2) | 2u | 1u);
  // The whole instance's RAM (212 words) was cleared.
  EXPECT_EQ(s.CountWritesIn(kRam, kRam + 0x34C), 212 + 2);
  EXPECT_EQ(s.Peek(kIe), (1u << 0) | (1u << 2) | (1u << 19));  // RF0NE, RF0LE, BOE
  EXPECT_EQ(s.Peek(kIls), 1u << 6);                            // PERR → line 1
  EXPECT_EQ(s.Peek(kIle), 3u);
  // NVIC: IRQ 21 and 22 enabled (ISER0 bits), priority 4 << 4 in IPR5 bytes 1 and 2.
  // (ISER is write-one-to-set: each enable is its own write.)
  EXPECT_EQ(s.WritesTo(0xE000E100), (std::vector<std::uint32_t>{1u << 21, 1u << 22}));
  EXPECT_EQ(s.Peek(0xE000E414), (0x40u << 8) | (0x40u << 16));
}

TEST(Stm32g4Fdcan, TooManyFiltersTouchesNothing) {
  ScriptedSpace s;
  Stm32g4Fdcan can;
  std::array<CanFilter, 29> filters{};
  EXPECT_EQ(can.Init(filters), FdcanResult::kTooManyFilters);
  EXPECT_TRUE(s.log.empty());
}

TEST(Stm32g4Fdcan, SendWritesTheTxElement) {
  ScriptedSpace s;
  auto can = Started(s);
  s.memory[kTxfqs] = (1u << 16) | 3u;  // put index 1, 3 free
  protocol::CanFrame f;
  f.id = 0x123;
  f.length = 3;
  f.data = {1, 2, 3};
  ASSERT_TRUE(can->Send(f));
  // Element 1 of the TX buffers: 0x278 + 72.
  constexpr Address kElement = kRam + 0x278 + 72;
  EXPECT_EQ(s.Peek(kElement), 0x123u << 18);  // XTD = 0, ID[28:18]
  EXPECT_EQ(s.Peek(kElement + 4), 3u << 16);  // DLC 3, classic
  EXPECT_EQ(s.Peek(kElement + 8), 0x00030201u);
  EXPECT_EQ(s.WritesTo(kTxbar), (std::vector<std::uint32_t>{1u << 1}));
  // The request comes after the element's last word.
  EXPECT_LT(s.FirstWrite(kElement + 8, testing::Any()),
            s.FirstWrite(kTxbar, testing::Any()));

  // An FD frame of 10 bytes goes out as DLC 9 (12 bytes), FDF and BRS, zero-padded.
  s.memory[kTxfqs] = (2u << 16) | 2u;
  protocol::CanFrame fd;
  fd.id = 0x7FF;
  fd.fd = true;
  fd.length = 10;
  for (std::uint8_t i = 0; i < 10; ++i) fd.data[i] = static_cast<std::uint8_t>(0xA0 + i);
  ASSERT_TRUE(can->Send(fd));
  constexpr Address kElement2 = kRam + 0x278 + 2 * 72;
  EXPECT_EQ(s.Peek(kElement2), 0x7FFu << 18);
  EXPECT_EQ(s.Peek(kElement2 + 4), (9u << 16) | (1u << 21) | (1u << 20));
  EXPECT_EQ(s.Peek(kElement2 + 16), 0x0000A9A8u);
  EXPECT_EQ(s.Peek(kTxbar), 1u << 2);

  s.memory[kTxfqs] = 1u << 21;  // TFQF: full
  EXPECT_FALSE(can->Send(f));
  EXPECT_EQ(can->counters().sent, 2u);
}

TEST(Stm32g4Fdcan, TransmitIsIdleOnlyWithEveryTxElementFree) {
  // TXFQS.TFFL (bits 2:0): free elements of the three-element TX FIFO (RM0440 §44.4).
  ScriptedSpace s;
  auto can = Started(s);
  s.memory[kTxfqs] = (1u << 16) | 3u;
  EXPECT_TRUE(can->TransmitIdle());
  s.memory[kTxfqs] = (2u << 16) | (1u << 8) | 2u;  // one frame still queued
  EXPECT_FALSE(can->TransmitIdle());
  s.memory[kTxfqs] = 1u << 21;  // full
  EXPECT_FALSE(can->TransmitIdle());
}

TEST(Stm32g4Fdcan, ReceiveDrainsFifo0) {
  ScriptedSpace s;
  auto can = Started(s);
  // One frame at get index 2: RX FIFO 0 element 2 at 0x0B0 + 2 × 72.
  constexpr Address kElement = kRam + 0x0B0 + 2 * 72;
  s.memory[kElement] = 0x321u << 18;
  s.memory[kElement + 4] = (12u << 16) | (1u << 21);  // DLC 12 → 24 bytes, FD
  for (std::uint32_t w = 0; w < 6; ++w) s.memory[kElement + 8 + 4 * w] = 0x01010101u * w;
  s.memory[kRxf0s] = (2u << 8) | 1u;
  s.memory[kIr] = 1u;  // RF0N
  s.log.clear();
  s.after_write = [&s](Address a, std::uint32_t) {
    if (a == kRxf0a) s.memory[kRxf0s] = 0;  // acknowledged: empty
  };
  can->ISR_Line0();
  EXPECT_EQ(s.WritesTo(kRxf0a), (std::vector<std::uint32_t>{2u}));
  EXPECT_EQ(s.WritesTo(kIr), (std::vector<std::uint32_t>{1u}));
  protocol::CanFrame f;
  ASSERT_TRUE(can->Receive(&f));
  EXPECT_EQ(f.id, 0x321u);
  EXPECT_TRUE(f.fd);
  EXPECT_EQ(f.length, 24);
  EXPECT_EQ(f.data[4], 1);
  EXPECT_EQ(f.data[23], 5);
  EXPECT_FALSE(can->Receive(&f));
  EXPECT_EQ(can->counters().received, 1u);
}

TEST(Stm32g4Fdcan, BusOffIsCountedAndRecovered) {
  ScriptedSpace s;
  auto can = Started(s);
  s.memory[kCccr] = kInit;          // the controller entered INIT on bus-off
  s.memory[kPsr] = (1u << 7) | 3u;  // BO, LEC = ack error
  s.memory[kIr] = 1u << 19;         // IR.BO
  s.memory[kEcr] = (9u << 8) | 255u;
  s.log.clear();
  can->ISR_Line1();
  EXPECT_EQ(s.WritesTo(kIr), (std::vector<std::uint32_t>{1u << 19}));
  EXPECT_EQ(s.Peek(kCccr) & kInit, 0u);  // recovery started
  EXPECT_EQ(can->TakeBusOff(), 1u);
  EXPECT_EQ(can->TakeBusOff(), 0u);
  const hal::CanPortCounters c = can->counters();
  EXPECT_EQ(c.bus_off, 1u);
  EXPECT_TRUE(c.bus_off_now);
  EXPECT_EQ(c.tx_errors, 255);
  EXPECT_EQ(c.rx_errors, 9);
  EXPECT_EQ(c.last_error, 3);
}

TEST(Stm32g4Fdcan, DlcCoding) {
  EXPECT_EQ(CanLengthToDlc(8), 8u);
  EXPECT_EQ(CanLengthToDlc(9), 9u);
  EXPECT_EQ(CanLengthToDlc(64), 15u);
  EXPECT_EQ(CanDlcToLength(15, true), 64);
  EXPECT_EQ(CanDlcToLength(15, false), 8);
  EXPECT_EQ(CanDlcToLength(13, true), 32);
}

}  // namespace
}  // namespace mjc::stm32g4
