#include "hal/stm32g4/fdcan.h"

#include "hal/stm32g4/mmio.h"
#include "hal/stm32g4/nvic.h"
#include "hal/stm32g4/poll.h"
#include "hal/stm32g4/regs/irq.h"

namespace mjc::stm32g4 {
namespace {

using namespace fdcan;

constexpr Address kRam = ram::kFdcan1;
constexpr std::uint32_t kMaxPolls = 100'000;

void SetBits(Address a, std::uint32_t bits) { Write32(a, Read32(a) | bits); }

}  // namespace

FdcanResult Stm32g4Fdcan::Init(std::span<const CanFilter> filters) {
  if (filters.size() > ram::kStdFilterCount) return FdcanResult::kTooManyFilters;
  const Address cccr = kBase + kCccr;

  // RM0440 §44.3.2 "Software initialization": leave sleep (CSR = 0, wait CSA = 0), set
  // INIT and wait until it reads 1, then CCE to unlock the protected registers.
  Write32(cccr, Read32(cccr) & ~cccr::kCsr.Bit());
  if (!WaitFor(cccr, cccr::kCsa.Bit(), 0, kMaxPolls)) return FdcanResult::kTimeout;
  SetBits(cccr, cccr::kInit.Bit());
  if (!WaitFor(cccr, cccr::kInit.Bit(), cccr::kInit.Bit(), kMaxPolls)) {
    return FdcanResult::kTimeout;
  }
  SetBits(cccr, cccr::kCce.Bit());

  // Kernel clock undivided (FDCAN_CONFIG.CKDIV, writable only now: INIT = CCE = 1).
  Write32(kConfigBase + kCkdiv, ckdiv::kPdiv.Value(0));

  // FD operation with bit-rate switching allowed; automatic retransmission on (DAR = 0);
  // protocol exception handling as ISO 11898-1:2015 (PXHD = 0).
  Write32(cccr, (Read32(cccr) & ~(cccr::kDar.Bit() | cccr::kPxhd.Bit())) |
                    cccr::kFdoe.Bit() | cccr::kBrse.Bit());

  Write32(kBase + kNbtp, nbtp::kNsjw.Value(kNominalTiming.sjw - 1) |
                             nbtp::kNbrp.Value(kNominalTiming.prescaler - 1) |
                             nbtp::kNtseg1.Value(kNominalTiming.seg1 - 1) |
                             nbtp::kNtseg2.Value(kNominalTiming.seg2 - 1));
  Write32(kBase + kDbtp, dbtp::kTdc.Bit() | dbtp::kDbrp.Value(kDataTiming.prescaler - 1) |
                             dbtp::kDtseg1.Value(kDataTiming.seg1 - 1) |
                             dbtp::kDtseg2.Value(kDataTiming.seg2 - 1) |
                             dbtp::kDsjw.Value(kDataTiming.sjw - 1));
  Write32(kBase + kTdcr, tdcr::kTdco.Value(kTdcOffset) | tdcr::kTdcf.Value(kTdcFilter));

  // The instance's message RAM starts undefined after power-up: clear all of it (32-bit
  // writes only, RM0440 §44.3.3), then write the filters.
  for (std::uint32_t offset = 0; offset < ram::kInstanceBytes; offset += 4) {
    Write32(kRam + offset, 0);
  }
  for (std::size_t i = 0; i < filters.size(); ++i) {
    const std::uint32_t element =
        (ram::kSftClassic << ram::kSftShift) | (ram::kSfecFifo0 << ram::kSfecShift) |
        ((filters[i].id & ram::kStdIdMask) << ram::kSfid1Shift) |
        (filters[i].mask & ram::kStdIdMask);
    Write32(kRam + ram::kStdFilters + 4 * static_cast<std::uint32_t>(i), element);
  }
  Write32(kBase + kRxgfc, rxgfc::kLss.Value(static_cast<std::uint32_t>(filters.size())) |
                              rxgfc::kLse.Value(0) | rxgfc::kAnfs.Value(0b10) |
                              rxgfc::kAnfe.Value(0b10) | rxgfc::kRrfs.Bit() |
                              rxgfc::kRrfe.Bit());
  Write32(kBase + kTxbc, txbc::kTfqm.Value(0));  // TX FIFO, not queue: sent in order

  // Interrupts: RX FIFO 0 group on line 0, protocol errors (bus-off) on line 1.
  // Stale flags of the enabled interrupts (write 1 to clear).
  Write32(kBase + kIr, ir::kRf0n.Bit() | ir::kRf0l.Bit() | ir::kBo.Bit());
  Write32(kBase + kIe, ie::kRf0ne.Bit() | ie::kRf0le.Bit() | ie::kBoe.Bit());
  Write32(kBase + kIls, ils::kPerr.Bit());
  Write32(kBase + kIle, ile::kEint0.Bit() | ile::kEint1.Bit());

  // Leave configuration: clearing INIT also clears CCE. The controller joins the bus
  // after 11 recessive bits.
  Write32(cccr, Read32(cccr) & ~(cccr::kInit.Bit() | cccr::kCce.Bit()));
  if (!WaitFor(cccr, cccr::kInit.Bit(), 0, kMaxPolls)) return FdcanResult::kTimeout;

  EnableIrq(irq::kFdcan1Line0, kPriorityCan);
  EnableIrq(irq::kFdcan1Line1, kPriorityCan);
  return FdcanResult::kOk;
}

void Stm32g4Fdcan::ISR_Line0() {
  // Clear first: a frame arriving while the FIFO is drained raises the line again.
  const std::uint32_t ir = Read32(kBase + kIr);
  Write32(kBase + kIr, ir & (ir::kRf0n.Bit() | ir::kRf0l.Bit()));
  if (ir::kRf0l.IsSet(ir)) {
    fifo_lost_.store(fifo_lost_.load(std::memory_order_relaxed) + 1,
                     std::memory_order_relaxed);
  }
  for (std::uint32_t guard = 0; guard < ram::kFifoElements; ++guard) {
    const std::uint32_t status = Read32(kBase + kRxf0s);
    if (rxf0s::kF0fl.Get(status) == 0) break;
    const std::uint32_t index = rxf0s::kF0gi.Get(status);
    const Address element = kRam + ram::kRxFifo0 + index * ram::kElementBytes;
    const std::uint32_t w0 = Read32(element);
    const std::uint32_t w1 = Read32(element + 4);
    // Only standard data frames pass the filters; anything else is dropped unread.
    if ((w0 & (ram::kXtd | ram::kRtr)) == 0) {
      protocol::CanFrame frame;
      frame.id = (w0 >> ram::kStdIdShift) & ram::kStdIdMask;
      frame.fd = (w1 & ram::kFdf) != 0;
      frame.length = CanDlcToLength((w1 >> ram::kDlcShift) & 0xFu, frame.fd);
      for (std::uint32_t i = 0; i < frame.length; i += 4) {
        const std::uint32_t word = Read32(element + 8 + i);
        for (std::uint32_t b = 0; b < 4 && i + b < frame.length; ++b) {
          frame.data[i + b] = static_cast<std::uint8_t>(word >> (8 * b));
        }
      }
      (void)rx_.Push(frame);  // a full queue counts the drop itself
    }
    Write32(kBase + kRxf0a, rxf0a::kF0ai.Value(index));
  }
}

void Stm32g4Fdcan::ISR_Line1() {
  const std::uint32_t ir = Read32(kBase + kIr);
  Write32(kBase + kIr, ir & ir::kBo.Bit());
  if (ir::kBo.IsSet(ir) && psr::kBo.IsSet(Read32(kBase + kPsr))) {
    bus_off_.store(bus_off_.load(std::memory_order_relaxed) + 1,
                   std::memory_order_release);
    // Recovery: INIT (set by the controller on bus-off) cleared; the controller then
    // waits 129 × 11 recessive bits (see the header).
    const Address cccr = kBase + kCccr;
    Write32(cccr, Read32(cccr) & ~(cccr::kInit.Bit() | cccr::kCce.Bit()));
  }
}

bool Stm32g4Fdcan::DoSend(const protocol::CanFrame& frame) {
  const std::size_t max = frame.fd ? 64 : 8;
  if (frame.length > max) return false;  // no controller can send it
  const std::uint32_t status = Read32(kBase + kTxfqs);
  if (txfqs::kTfqf.IsSet(status)) return false;
  const std::uint32_t index = txfqs::kTfqpi.Get(status);
  const Address element = kRam + ram::kTxBuffers + index * ram::kElementBytes;
  Write32(element, (frame.id & ram::kStdIdMask) << ram::kStdIdShift);
  const std::uint32_t dlc = CanLengthToDlc(frame.length);
  Write32(element + 4,
          (dlc << ram::kDlcShift) | (frame.fd ? (ram::kFdf | ram::kBrs) : 0u));
  // Whole words up to the DLC's length (an FD length between the steps is padded with
  // zeros to the next one).
  const std::uint32_t bytes = CanDlcToLength(dlc, frame.fd);
  for (std::uint32_t i = 0; i < bytes; i += 4) {
    std::uint32_t word = 0;
    for (std::uint32_t b = 0; b < 4; ++b) {
      if (i + b < frame.length) word |= std::uint32_t{frame.data[i + b]} << (8 * b);
    }
    Write32(element + 8 + i, word);
  }
  // The element is complete before its request is (the bus orders the writes).
  Write32(kBase + kTxbar, txbar::kAr.Value(1u << index));
  sent_.store(sent_.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
  return true;
}

bool Stm32g4Fdcan::TransmitIdle() const {
  return txfqs::kTffl.Get(Read32(kBase + kTxfqs)) == ram::kFifoElements;
}

bool Stm32g4Fdcan::DoReceive(protocol::CanFrame* frame) {
  if (!rx_.Pop(frame)) return false;
  received_.store(received_.load(std::memory_order_relaxed) + 1,
                  std::memory_order_relaxed);
  return true;
}

std::uint32_t Stm32g4Fdcan::DoTakeBusOff() {
  const std::uint32_t total = bus_off_.load(std::memory_order_acquire);
  const std::uint32_t taken = bus_off_taken_.load(std::memory_order_relaxed);
  bus_off_taken_.store(total, std::memory_order_relaxed);
  return total - taken;
}

hal::CanPortCounters Stm32g4Fdcan::DoCounters() const {
  hal::CanPortCounters c;
  c.received = received_.load(std::memory_order_relaxed);
  c.rx_overflow = rx_.dropped() + fifo_lost_.load(std::memory_order_relaxed);
  c.sent = sent_.load(std::memory_order_relaxed);
  c.bus_off = bus_off_.load(std::memory_order_relaxed);
  const std::uint32_t ecr = Read32(kBase + kEcr);
  c.tx_errors = static_cast<std::uint8_t>(ecr::kTec.Get(ecr));
  c.rx_errors = static_cast<std::uint8_t>(ecr::kRec.Get(ecr));
  const std::uint32_t psr = Read32(kBase + kPsr);  // reading resets LEC to 7
  c.error_warning = psr::kEw.IsSet(psr);
  c.error_passive = psr::kEp.IsSet(psr);
  c.bus_off_now = psr::kBo.IsSet(psr);
  c.last_error = static_cast<std::uint8_t>(psr::kLec.Get(psr));
  return c;
}

}  // namespace mjc::stm32g4
