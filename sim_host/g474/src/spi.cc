#include "mjc/g474model/spi.h"

#include <string>

namespace mjc::g474model {
namespace {
constexpr std::uint32_t kMstr = 1u << 2, kSpe = 1u << 6, kSsi = 1u << 8, kSsm = 1u << 9;
constexpr std::uint32_t kFrxth = 1u << 12;
}  // namespace

Spi::Spi(ViolationLog* log, const Rcc* rcc) : log_(log), rcc_(rcc) { Reset(); }

void Spi::Reset() {
  cr1_ = 0;
  cr2_ = 0x700;  // DS = 0111: 8 bits
  crcpr_ = 7;
  i2scfgr_ = 0;
  i2spr_ = 2;
  ovr_ = modf_ = ovr_armed_ = false;
  tx_.clear();
  rx_.clear();
  busy_ = false;
}

unsigned Spi::frame_bits() const { return ((cr2_ >> 8) & 0xFu) + 1; }

double Spi::sck_hz() const {
  return rcc_->pclk2_hz() / static_cast<double>(2u << ((cr1_ >> 3) & 7u));
}

std::uint32_t Spi::Sr() const {
  const std::size_t rxn = rx_.size(), txn = tx_.size();
  std::uint32_t sr = 0;
  if (rxn >= ((cr2_ & kFrxth) ? 1u : 2u)) sr |= 1u;  // RXNE
  if (txn <= 2) sr |= 2u;                            // TXE
  if (modf_) sr |= 1u << 5;
  if (ovr_) sr |= 1u << 6;
  if (busy_ || (txn > 0 && (cr1_ & kSpe))) sr |= 1u << 7;
  auto level = [](std::size_t n) { return n >= 4 ? 3u : n >= 2 ? 2u : n >= 1 ? 1u : 0u; };
  sr |= level(rxn) << 9;
  sr |= level(txn) << 11;
  return sr;
}

bool Spi::irq() const {
  if ((cr2_ & 0xE0u) == 0) return false;  // RXNEIE, TXEIE, ERRIE all clear
  const std::uint32_t sr = Sr();
  return ((cr2_ & (1u << 6)) && (sr & 1u)) || ((cr2_ & (1u << 7)) && (sr & 2u)) ||
         ((cr2_ & (1u << 5)) && (ovr_ || modf_));
}

void Spi::StartNext() {
  if (busy_ || !(cr1_ & kSpe) || !(cr1_ & kMstr)) return;
  const unsigned nbytes = FrameBytes();
  if (tx_.size() < nbytes) return;
  std::uint16_t word = tx_.front();
  tx_.pop_front();
  if (nbytes == 2) {
    word = static_cast<std::uint16_t>(word | (tx_.front() << 8));
    tx_.pop_front();
  }
  const unsigned bits = frame_bits();
  current_ = SpiFrame{};
  current_.mosi = static_cast<std::uint16_t>(word & ((1u << bits) - 1u));
  current_.bits = bits;
  current_.cpha = cr1_ & 1u;
  current_.cpol = (cr1_ >> 1) & 1u;
  current_.lsb_first = (cr1_ >> 7) & 1u;
  current_.sck_hz = sck_hz();
  current_.start = now_;
  current_.end = current_.sck_hz > 0
                     ? now_ + static_cast<Picoseconds>(static_cast<double>(bits) /
                                                       current_.sck_hz * 1e12)
                     : kNever;
  busy_ = true;
  if (start_hook_) start_hook_(current_);
}

void Spi::Advance(Picoseconds now) {
  now_ = now;
  while (busy_ && now >= current_.end) {
    const Picoseconds end = current_.end;
    busy_ = false;
    const std::uint16_t miso = bus_ ? bus_(current_) : 0;
    const unsigned nbytes = FrameBytes();
    if (rx_.size() + nbytes > 4) {
      ovr_ = true;  // the FIFO is full: the frame is lost
    } else {
      rx_.push_back(static_cast<std::uint8_t>(miso & 0xFFu));
      if (nbytes == 2) rx_.push_back(static_cast<std::uint8_t>(miso >> 8));
    }
    const Picoseconds save = now_;
    now_ = end;  // back-to-back frames start where the previous one ended
    StartNext();
    now_ = save;
  }
}

Picoseconds Spi::NextEvent() const { return busy_ ? current_.end : kNever; }

RegisterTable<Spi> Spi::Registers() {
  using R = Register<Spi>;
  // SR and DR read and write through code of their own; CR1 and CR2 have side effects
  // after the write (see Read and Write).
  static constexpr R kTable[] = {
      R::ReadWrite(0x00, &Spi::cr1_, 0xFFFFu),
      R::ReadWrite(0x04, &Spi::cr2_, 0x7FFFu),
      R::ReadWrite(0x10, &Spi::crcpr_, 0xFFFFu),
      R::Fixed(0x14),  // RXCRCR: CRC not modelled
      R::Fixed(0x18),  // TXCRCR
      R::ReadWrite(0x1C, &Spi::i2scfgr_),
      R::ReadWrite(0x20, &Spi::i2spr_),
  };
  return kTable;
}

bool Spi::Read(const Access& a, std::uint32_t* v) {
  switch (a.offset) {
    case 0x08:
      *v = Sr();
      if (ovr_armed_) ovr_ = ovr_armed_ = false;  // DR read then SR read clears OVR
      return true;
    case 0x0C: {
      if (a.bytes == 4)
        log_->Report(now_, "SPI1", "32-bit read of SPI_DR (16-bit register)");
      // A 16-bit read takes two bytes from the FIFO (two ≤ 8-bit frames or one frame).
      std::uint32_t r = 0;
      if (rx_.size() < 2) {
        log_->Report(now_, "SPI1",
                     "16-bit read of DR with " + std::to_string(rx_.size()) +
                         " byte(s) in the RX FIFO (RM0440 data packing)");
      }
      for (unsigned i = 0; i < 2 && !rx_.empty(); ++i) {
        r |= static_cast<std::uint32_t>(rx_.front()) << (8 * i);
        rx_.pop_front();
      }
      if (ovr_) ovr_armed_ = true;
      *v = r;
      return true;
    }
    default:
      return ReadTableRegister(Registers(), *this, a.offset, v);
  }
}

bool Spi::Write(const Access& a) {
  switch (a.offset) {
    case 0x08:
      return true;  // the flags are cleared by their sequences
    case 0x0C: {
      if (a.bytes == 4)
        log_->Report(now_, "SPI1", "32-bit write of SPI_DR (16-bit register)");
      const std::uint32_t v = a.value & 0xFFFFu;
      for (unsigned i = 0; i < 2; ++i) {
        if (tx_.size() >= 4) {
          log_->Report(now_, "SPI1", "write to DR with the TX FIFO full: data lost");
          break;
        }
        tx_.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
      }
      StartNext();
      return true;
    }
    default:
      break;
  }
  const std::uint32_t before = cr1_;
  if (!WriteTableRegister(Registers(), *this, a)) return false;
  if (a.offset == 0x00) {
    if ((before & kSpe) && !(cr1_ & kSpe) && (busy_ || !tx_.empty())) {
      log_->Report(now_, "SPI1",
                   "SPE cleared during a transfer (wait for FTLVL = 0 and BSY = 0 "
                   "first, RM0440 'Disabling the SPI')");
      busy_ = false;
      tx_.clear();
    }
    if ((cr1_ & kMstr) && (cr1_ & kSpe) && (cr1_ & kSsm) && !(cr1_ & kSsi)) {
      // Master with software NSS low: mode fault.
      modf_ = true;
      cr1_ &= ~(kSpe | kMstr);
      log_->Report(now_, "SPI1", "MODF: master enabled with SSM = 1 and SSI = 0");
    }
    StartNext();
  } else if (a.offset == 0x04) {
    const unsigned ds = (cr2_ >> 8) & 0xFu;
    if (ds < 3) {
      cr2_ = (cr2_ & ~(0xFu << 8)) | (7u << 8);  // "not used" values: forced to 8 bits
      log_->Report(now_, "SPI1", "CR2.DS = " + std::to_string(ds) + " not used: 8 bits");
    }
  }
  return true;
}

}  // namespace mjc::g474model
