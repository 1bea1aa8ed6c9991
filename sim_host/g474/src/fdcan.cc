#include "mjc/g474model/fdcan.h"

#include <cstring>
#include <string>

namespace mjc::g474model {
namespace {
// Message RAM layout of one instance (RM0440 "FDCAN message RAM"; ST HAL
// stm32g4xx_hal_fdcan.c, SRAMCAN_*).
constexpr std::uint32_t kFlssa = 0x000, kFlesa = 0x070, kRf0sa = 0x0B0, kRf1sa = 0x188,
                        kTefsa = 0x260, kTfqsa = 0x278, kElement = 72;
constexpr std::uint32_t kInit = 1u << 0, kCce = 1u << 1, kCsa = 1u << 3, kCsr = 1u << 4;
constexpr std::uint32_t kCccrProtected = (1u << 2) | (1u << 5) | (1u << 6) | (1u << 7) |
                                         (1u << 8) | (1u << 9) | (1u << 12) | (1u << 13) |
                                         (1u << 14) | (1u << 15);
// IR bits.
constexpr std::uint32_t kRf0n = 1u << 0, kRf0f = 1u << 1, kRf0l = 1u << 2, kTc = 1u << 7,
                        kTcf = 1u << 8, kTfe = 1u << 9, kTefn = 1u << 10,
                        kTeff = 1u << 11, kTefl = 1u << 12, kEp = 1u << 17,
                        kEw = 1u << 18, kBo = 1u << 19, kHpm = 1u << 6;
// The G4's interrupt groups (ILS bit for each IR bit), RM0440 FDCAN_ILS.
constexpr int kGroupOf[24] = {0, 0, 0, 1, 1, 1, 2, 2, 2, 3, 3, 3,
                              3, 4, 4, 4, 5, 5, 6, 6, 6, 6, 6, 6};
}  // namespace

std::uint8_t DlcToLength(std::uint8_t dlc, bool fd) {
  static constexpr std::uint8_t kFd[16] = {0, 1,  2,  3,  4,  5,  6,  7,
                                           8, 12, 16, 20, 24, 32, 48, 64};
  dlc &= 0xFu;
  if (!fd) return dlc > 8 ? 8 : dlc;
  return kFd[dlc];
}

std::uint8_t LengthToDlc(std::uint8_t length) {
  for (std::uint8_t d = 0; d < 16; ++d) {
    if (DlcToLength(d, true) >= length) return d;
  }
  return 15;
}

Fdcan::Fdcan(ViolationLog* log, const Rcc* rcc) : log_(log), rcc_(rcc) { Reset(); }

void Fdcan::Reset() {
  ram_.fill(0);  // SRAM content is not defined at reset; zero here
  ckdiv_ = 0;
  dbtp_ = 0x00000A33u;
  test_ = rwd_ = 0;
  cccr_ = kInit;
  nbtp_ = 0x06000A03u;
  tscc_ = 0;
  tocc_ = 0xFFFF0000u;
  ecr_ = 0;
  psr_ = 0x00000707u;
  tdcr_ = ir_ = ie_ = ils_ = ile_ = rxgfc_ = 0;
  xidam_ = 0x1FFFFFFFu;
  hpms_ = txbc_ = txbrp_ = txbto_ = txbcf_ = txbtie_ = txbcie_ = 0;
  rx_ = {};
  tx_event_ = {};
  tx_get_ = tx_put_ = 0;
  tx_free_ = 3;
  synced_at_ = recovered_at_ = kNever;
  tx_current_ = -1;
  tx_end_ = kNever;
}

double Fdcan::kernel_hz() const {
  const unsigned pdiv = ckdiv_ & 0xFu;
  return rcc_->fdcan_kernel_hz() / (pdiv == 0 ? 1.0 : 2.0 * pdiv);
}
double Fdcan::nominal_bitrate() const {
  const double tq = 1.0 + (((nbtp_ >> 8) & 0xFFu) + 1) + ((nbtp_ & 0x7Fu) + 1);
  return kernel_hz() / ((((nbtp_ >> 16) & 0x1FFu) + 1) * tq);
}
double Fdcan::data_bitrate() const {
  const double tq = 1.0 + (((dbtp_ >> 8) & 0x1Fu) + 1) + (((dbtp_ >> 4) & 0xFu) + 1);
  return kernel_hz() / ((((dbtp_ >> 16) & 0x1Fu) + 1) * tq);
}
double Fdcan::nominal_sample_point() const {
  const double seg1 = ((nbtp_ >> 8) & 0xFFu) + 1.0, seg2 = (nbtp_ & 0x7Fu) + 1.0;
  return (1 + seg1) / (1 + seg1 + seg2);
}
double Fdcan::data_sample_point() const {
  const double seg1 = ((dbtp_ >> 8) & 0x1Fu) + 1.0, seg2 = ((dbtp_ >> 4) & 0xFu) + 1.0;
  return (1 + seg1) / (1 + seg1 + seg2);
}

bool Fdcan::active() const {
  return !(cccr_ & kInit) && !bus_off() && now_ >= synced_at_ && synced_at_ != kNever;
}

bool Fdcan::line0() const {
  if (!(ile_ & 1u)) return false;
  const std::uint32_t on = ir_ & ie_;
  if (on == 0) return false;
  for (int b = 0; b < 24; ++b) {
    if ((on >> b) & 1u && !((ils_ >> kGroupOf[b]) & 1u)) return true;
  }
  return false;
}
bool Fdcan::line1() const {
  if (!(ile_ & 2u)) return false;
  const std::uint32_t on = ir_ & ie_;
  if (on == 0) return false;
  for (int b = 0; b < 24; ++b) {
    if ((on >> b) & 1u && ((ils_ >> kGroupOf[b]) & 1u)) return true;
  }
  return false;
}

bool Fdcan::Protected(const char* reg) {
  if ((cccr_ & kInit) && (cccr_ & kCce)) return true;
  log_->Report(now_, "FDCAN1",
               std::string(reg) +
                   " written without CCCR.INIT = CCE = 1: ignored (protected register, "
                   "RM0440 §44.4)");
  return false;
}

std::uint32_t Fdcan::Timestamp() const {
  if ((tscc_ & 3u) != 1) return 0;
  const double bits = static_cast<double>(now_ - ts_origin_) * 1e-12 * nominal_bitrate();
  const auto ticks = static_cast<std::uint64_t>(bits) / (((tscc_ >> 16) & 0xFu) + 1);
  return static_cast<std::uint32_t>(ticks & 0xFFFFu);
}

Picoseconds Fdcan::FrameDuration(const CanBusFrame& f) const {
  const double nominal = nominal_bitrate(), data = data_bitrate();
  if (nominal <= 0) return kNever;
  const double n = f.length;
  double nominal_bits, data_bits = 0;
  if (!f.fd) {
    nominal_bits = (f.extended ? 67 : 47) + (f.remote ? 0 : 8 * n);
  } else {
    nominal_bits = (f.extended ? 37 : 17) + 12;
    const double payload = 1 + 4 + 8 * n + 4 + (n <= 16 ? 17 : 21) + 1;
    if (f.brs && data > 0) {
      data_bits = payload;
    } else {
      nominal_bits += payload;
    }
  }
  const double s = nominal_bits / nominal + (data_bits > 0 ? data_bits / data : 0);
  return static_cast<Picoseconds>(s * 1e12);
}

CanBusFrame Fdcan::ReadTxElement(int index) const {
  const std::uint32_t base = kTfqsa + static_cast<std::uint32_t>(index) * kElement;
  const std::uint32_t t0 = Word(base), t1 = Word(base + 4);
  CanBusFrame f;
  f.extended = (t0 >> 30) & 1u;
  f.remote = (t0 >> 29) & 1u;
  f.esi = (t0 >> 31) & 1u;
  f.id = f.extended ? (t0 & 0x1FFFFFFFu) : ((t0 >> 18) & 0x7FFu);
  f.fd = ((t1 >> 21) & 1u) && (cccr_ & (1u << 8));  // FDF only with CCCR.FDOE
  f.brs = f.fd && ((t1 >> 20) & 1u) && (cccr_ & (1u << 9));
  f.dlc = static_cast<std::uint8_t>((t1 >> 16) & 0xFu);
  f.length = DlcToLength(f.dlc, f.fd);
  for (std::uint32_t i = 0; i < f.length; ++i) {
    f.data[i] = static_cast<std::uint8_t>(Word(base + 8 + (i & ~3u)) >> (8 * (i & 3u)));
  }
  return f;
}

void Fdcan::TryStartTx() {
  if (tx_current_ >= 0 || !active() || !(txbrp_ & (1u << tx_get_))) return;
  if (!tx_routed_) return;  // nothing leaves through an unrouted pin
  tx_current_ = static_cast<int>(tx_get_);
  tx_end_ = now_ + FrameDuration(ReadTxElement(tx_current_));
  psr_ = (psr_ & ~(3u << 3)) | (3u << 3);  // ACT = transmitter
}

void Fdcan::Advance(Picoseconds now) {
  now_ = now;
  if (recovered_at_ != kNever && now >= recovered_at_) {
    // Bus-off recovery complete: 129 × 11 recessive bits seen.
    recovered_at_ = kNever;
    psr_ &= ~((1u << 7) | (1u << 6) | (1u << 5));
    ecr_ &= ~0x7FFFu;
    SetIr(kBo | kEw | kEp);
    synced_at_ = now;
  }
  if ((psr_ & (3u << 3)) == 0 && active()) psr_ |= 1u << 3;  // ACT: idle
  while (tx_current_ >= 0 && now >= tx_end_) {
    const Picoseconds end = tx_end_;
    const CanBusFrame f = ReadTxElement(tx_current_);
    const std::uint32_t bit = 1u << tx_current_;
    const std::uint32_t t1 =
        Word(kTfqsa + static_cast<std::uint32_t>(tx_current_) * kElement + 4);
    txbrp_ &= ~bit;
    txbto_ |= bit;
    if (txbtie_ & bit) SetIr(kTc);
    tx_get_ = (tx_get_ + 1) % 3;
    ++tx_free_;
    if (tx_free_ == 3) SetIr(kTfe);
    if ((t1 >> 23) & 1u) {  // EFC: store a TX event
      if (tx_event_.fill == 3) {
        SetIr(kTefl);
      } else {
        const std::uint32_t e = kTefsa + tx_event_.put * 8;
        ram_[e / 4] = Word(kTfqsa + static_cast<std::uint32_t>(tx_current_) * kElement);
        ram_[e / 4 + 1] =
            (t1 & 0xFF000000u) | (1u << 22) | (t1 & 0x003F0000u) | Timestamp();
        tx_event_.put = (tx_event_.put + 1) % 3;
        ++tx_event_.fill;
        SetIr(kTefn);
        if (tx_event_.fill == 3) SetIr(kTeff);
      }
    }
    psr_ &= ~7u;  // LEC = 0: transferred without error
    psr_ = (psr_ & ~(3u << 3)) | (1u << 3);
    tx_current_ = -1;
    tx_end_ = kNever;
    if (tx_hook_) tx_hook_(f, end);
    const Picoseconds save = now_;
    now_ = end;
    TryStartTx();
    now_ = save;
  }
  TryStartTx();
}

Picoseconds Fdcan::NextEvent() const {
  Picoseconds next = tx_end_;
  if (recovered_at_ < next) next = recovered_at_;
  if (synced_at_ > now_ && synced_at_ < next) next = synced_at_;
  return next;
}

void Fdcan::InjectBusOff() {
  psr_ |= (1u << 7) | (1u << 6) | (1u << 5);
  ecr_ = (ecr_ & ~0xFFu) | 0xFFu;
  SetIr(kBo | kEw | kEp);
  cccr_ |= kInit;
  cccr_ &= ~kCce;
  tx_current_ = -1;  // the frame in flight stays pending
  tx_end_ = kNever;
  synced_at_ = kNever;
  recovered_at_ = kNever;
}

bool Fdcan::StoreInFifo(int fifo, const CanBusFrame& f, int filter_index, bool anmf) {
  Fifo& q = rx_[static_cast<std::size_t>(fifo)];
  const std::uint32_t shift = fifo == 0 ? 0 : 3;
  const bool overwrite = (rxgfc_ >> (fifo == 0 ? 9 : 8)) & 1u;
  if (q.fill == 3) {
    if (!overwrite) {
      SetIr(kRf0l << shift);
      return false;
    }
    q.get = (q.get + 1) % 3;
    --q.fill;
  }
  const std::uint32_t base = (fifo == 0 ? kRf0sa : kRf1sa) + q.put * kElement;
  ram_[base / 4] = (f.esi ? 1u << 31 : 0) | (f.extended ? 1u << 30 : 0) |
                   (f.remote ? 1u << 29 : 0) |
                   (f.extended ? (f.id & 0x1FFFFFFFu) : ((f.id & 0x7FFu) << 18));
  ram_[base / 4 + 1] = (anmf ? 1u << 31 : 0) |
                       (static_cast<std::uint32_t>(filter_index & 0x7F) << 24) |
                       (f.fd ? 1u << 21 : 0) | (f.brs ? 1u << 20 : 0) |
                       (static_cast<std::uint32_t>(f.dlc & 0xFu) << 16) | Timestamp();
  for (std::uint32_t w = 0; w < 16; ++w) {
    std::uint32_t word = 0;
    for (std::uint32_t b = 0; b < 4; ++b) {
      word |= static_cast<std::uint32_t>(f.data[w * 4 + b]) << (8 * b);
    }
    ram_[base / 4 + 2 + w] = word;
  }
  q.put = (q.put + 1) % 3;
  ++q.fill;
  SetIr(kRf0n << shift);
  if (q.fill == 3) SetIr(kRf0f << shift);
  return true;
}

bool Fdcan::Receive(const CanBusFrame& in) {
  if (!active() || !rx_routed_) return false;
  CanBusFrame f = in;
  f.length = DlcToLength(f.dlc, f.fd);
  if (f.fd) psr_ |= (1u << 13) | (f.brs ? 1u << 12 : 0) | (f.esi ? 1u << 11 : 0);
  psr_ &= ~7u;
  if (f.remote && ((rxgfc_ >> (f.extended ? 0 : 1)) & 1u)) return true;  // RRFx
  // action: 1 FIFO0, 2 FIFO1, 3 reject, 4 priority only, 5/6 priority + FIFO0/1.
  int action = -1, index = -1;
  if (!f.extended) {
    const std::uint32_t lss = std::min<std::uint32_t>(28, (rxgfc_ >> 16) & 0x1Fu);
    for (std::uint32_t i = 0; i < lss && action < 0; ++i) {
      const std::uint32_t e = Word(kFlssa + 4 * i);
      const std::uint32_t sft = e >> 30, sfec = (e >> 27) & 7u;
      const std::uint32_t id1 = (e >> 16) & 0x7FFu, id2 = e & 0x7FFu;
      if (sfec == 0 || sfec == 7 || sft == 3) continue;
      bool match = false;
      if (sft == 0) match = f.id >= id1 && f.id <= id2;
      if (sft == 1) match = f.id == id1 || f.id == id2;
      if (sft == 2) match = (f.id & id2) == (id1 & id2);
      if (match) action = static_cast<int>(sfec), index = static_cast<int>(i);
    }
  } else {
    const std::uint32_t lse = std::min<std::uint32_t>(8, (rxgfc_ >> 24) & 0xFu);
    for (std::uint32_t i = 0; i < lse && action < 0; ++i) {
      const std::uint32_t f0 = Word(kFlesa + 8 * i), f1 = Word(kFlesa + 8 * i + 4);
      const std::uint32_t efec = f0 >> 29, eft = f1 >> 30;
      const std::uint32_t id1 = f0 & 0x1FFFFFFFu, id2 = f1 & 0x1FFFFFFFu;
      if (efec == 0 || efec == 7) continue;
      const std::uint32_t id = eft == 3 ? f.id : (f.id & xidam_);
      bool match = false;
      if (eft == 0 || eft == 3) match = id >= id1 && id <= id2;
      if (eft == 1) match = id == id1 || id == id2;
      if (eft == 2) match = (id & id2) == (id1 & id2);
      if (match) action = static_cast<int>(efec), index = static_cast<int>(i);
    }
  }
  if (action < 0) {
    const std::uint32_t anf = (rxgfc_ >> (f.extended ? 2 : 4)) & 3u;
    if (anf >= 2) return true;  // rejected
    StoreInFifo(static_cast<int>(anf), f, 0, true);
    return true;
  }
  if (action >= 4) {
    SetIr(kHpm);
    hpms_ = (static_cast<std::uint32_t>(index) << 8) | (f.extended ? 1u << 15 : 0) |
            ((action == 4   ? 1u
              : action == 5 ? 2u
                            : 3u)
             << 6);
  }
  if (action == 1 || action == 5) StoreInFifo(0, f, index, false);
  if (action == 2 || action == 6) StoreInFifo(1, f, index, false);
  return true;
}

RegisterTable<Fdcan> Fdcan::Registers() {
  using R = Register<Fdcan>;
  // CCCR, TSCV, the FIFO acknowledges, TXBAR and TXBCR write through code of their
  // own, and the status registers computed from the queues read through it (see Read
  // and Write); ProtectedName lists the registers locked outside INIT = CCE = 1.
  static constexpr R kTable[] = {
      R::Fixed(0x00, 0x32141218u),  // CREL
      R::Fixed(0x04, 0x87654321u),  // ENDN
      R::ReadWrite(0x0C, &Fdcan::dbtp_, 0x009F1FFFu),
      R::ReadWrite(0x10, &Fdcan::test_, 0x70u),
      R::ReadWrite(0x14, &Fdcan::rwd_, 0xFFu),
      R::ReadWrite(0x18, &Fdcan::cccr_),
      R::ReadWrite(0x1C, &Fdcan::nbtp_, 0xFFFFFF7Fu),
      R::ReadWrite(0x20, &Fdcan::tscc_, 0x000F0003u),
      R::ReadWrite(0x28, &Fdcan::tocc_, 0xFFFF0007u),
      R::Fixed(0x2C, 0xFFFF),  // TOCV
      R::ReadWrite(0x48, &Fdcan::tdcr_, 0x7F7Fu),
      R::ClearByWriting1(0x50, &Fdcan::ir_, 0x00FFFFFFu),
      R::ReadWrite(0x54, &Fdcan::ie_, 0x00FFFFFFu),
      R::ReadWrite(0x58, &Fdcan::ils_, 0x7Fu),
      R::ReadWrite(0x5C, &Fdcan::ile_, 3u),
      R::ReadWrite(0x80, &Fdcan::rxgfc_, 0x0F1F033Fu),
      R::ReadWrite(0x84, &Fdcan::xidam_, 0x1FFFFFFFu),
      R::ReadOnly(0x88, &Fdcan::hpms_),
      R::Fixed(0x94),  // RXF0A
      R::Fixed(0x9C),  // RXF1A
      R::ReadWrite(0xC0, &Fdcan::txbc_, 1u << 24),
      R::ReadOnly(0xC8, &Fdcan::txbrp_),
      R::Fixed(0xCC),  // TXBAR
      R::Fixed(0xD0),  // TXBCR
      R::ReadOnly(0xD4, &Fdcan::txbto_),
      R::ReadOnly(0xD8, &Fdcan::txbcf_),
      R::ReadWrite(0xDC, &Fdcan::txbtie_, 7u),
      R::ReadWrite(0xE0, &Fdcan::txbcie_, 7u),
      R::Fixed(0xE8),  // TXEFA
  };
  return kTable;
}

namespace {
// The registers software may write only with CCCR.INIT = CCE = 1 (RM0440 FDCAN
// "protected write"), by name for the report; null for the others.
const char* ProtectedName(std::uint32_t offset) {
  switch (offset) {
    case 0x0C:
      return "DBTP";
    case 0x10:
      return "TEST";
    case 0x14:
      return "RWD";
    case 0x1C:
      return "NBTP";
    case 0x20:
      return "TSCC";
    case 0x28:
      return "TOCC";
    case 0x48:
      return "TDCR";
    case 0x80:
      return "RXGFC";
    case 0x84:
      return "XIDAM";
    case 0xC0:
      return "TXBC";
    default:
      return nullptr;
  }
}
}  // namespace

bool Fdcan::Read(const Access& a, std::uint32_t* v) {
  auto fifo_status = [&](int i) {
    const Fifo& q = rx_[static_cast<std::size_t>(i)];
    const bool lost = (ir_ >> (2 + 3 * i)) & 1u;
    return q.fill | (q.get << 8) | (q.put << 16) | (q.fill == 3 ? 1u << 24 : 0) |
           (lost ? 1u << 25 : 0);
  };
  switch (a.offset) {
    case 0x24:
      *v = Timestamp();
      return true;
    case 0x40:
      *v = ecr_;
      ecr_ &= ~(0xFFu << 16);
      return true;  // CEL reset on read
    case 0x44: {
      std::uint32_t p = psr_;
      if (recovered_at_ != kNever) {
        // During recovery LEC shows Bit0Error for each 11 recessive bits seen.
        const double bits =
            static_cast<double>(now_ - recovery_start_) * 1e-12 * nominal_bitrate();
        if (bits >= 11) p = (p & ~7u) | 5u;
      }
      *v = p;
      // LEC/DLEC set to 7 on read; RESI, RBRS, REDL reset on read.
      psr_ = (psr_ | 7u | (7u << 8)) & ~((1u << 11) | (1u << 12) | (1u << 13));
      return true;
    }
    case 0x90:
      *v = fifo_status(0);
      return true;
    case 0x98:
      *v = fifo_status(1);
      return true;
    case 0xC4:
      *v = tx_free_ | (tx_get_ << 8) | (tx_put_ << 16) | (tx_free_ == 0 ? 1u << 21 : 0);
      return true;
    case 0xE4:
      *v = tx_event_.fill | (tx_event_.get << 8) | (tx_event_.put << 16) |
           (tx_event_.fill == 3 ? 1u << 24 : 0) | ((ir_ & kTefl) ? 1u << 25 : 0);
      return true;
    default:
      return ReadTableRegister(Registers(), *this, a.offset, v);
  }
}

bool Fdcan::Write(const Access& a) {
  const std::uint32_t v = a.value & a.mask;
  switch (a.offset) {
    case 0x18: {
      const std::uint32_t next = a.Merged(cccr_);
      const bool was_init = cccr_ & kInit, was_cce = cccr_ & kCce;
      std::uint32_t c = cccr_;
      if ((next ^ c) & kCccrProtected) {
        if (was_init && was_cce) {
          c = (c & ~kCccrProtected) | (next & kCccrProtected);
        } else {
          log_->Report(now_, "FDCAN1",
                       "CCCR configuration bits written without INIT = CCE = 1: ignored");
        }
      }
      c = (c & ~kCsr) | (next & kCsr);
      if (c & kCsr) {
        c |= kInit | kCsa;  // clock stop: INIT, then CSA (no transfer pending here)
      } else {
        c &= ~kCsa;
      }
      const bool init = (next & kInit) || (c & kCsr);
      if (init) {
        if (!was_init) {
          tx_current_ = -1;
          tx_end_ = kNever;
        }
        c |= kInit;
        // CCE can be set only while INIT = 1 (already before this write).
        if (was_init && (next & kCce)) c |= kCce;
        if (!(next & kCce)) c &= ~kCce;
        if (!was_init && (next & kCce)) {
          log_->Report(now_, "FDCAN1",
                       "CCE set in the same write that sets INIT: CCE can only be set "
                       "while INIT = 1; ignored");
        }
      } else {
        c &= ~(kInit | kCce);  // leaving INIT clears CCE
        if (was_init) {
          const double bit = nominal_bitrate() > 0 ? 1.0 / nominal_bitrate() : 0;
          if (kernel_hz() <= 0) {
            log_->Report(now_, "FDCAN1", "INIT cleared with no FDCAN kernel clock");
          }
          if (bus_off()) {
            recovery_start_ = now_;
            recovered_at_ = now_ + static_cast<Picoseconds>(129 * 11 * bit * 1e12);
            synced_at_ = kNever;
          } else {
            synced_at_ = now_ + static_cast<Picoseconds>(11 * bit * 1e12);
            ts_origin_ = now_;
          }
          if (txbc_ & (1u << 24)) {
            log_->Report(now_, "FDCAN1", "TXBC.TFQM = 1 (TX queue) is not modelled");
          }
        }
      }
      cccr_ = c;
      return true;
    }
    case 0x24:
      ts_origin_ = now_;
      return true;  // a write resets the counter
    case 0x40:
    case 0x44:
    case 0x90:
    case 0x98:
    case 0xC4:
    case 0xE4:
      return true;  // read-only
    case 0x94:
    case 0x9C: {
      Fifo& q = rx_[a.offset == 0x94 ? 0 : 1];
      const unsigned ai = v & 7u;
      const unsigned n = (ai + 3 - q.get) % 3 + 1;
      if (ai > 2 || q.fill == 0 || n > q.fill) {
        log_->Report(now_, "FDCAN1",
                     "RXF" + std::to_string(a.offset == 0x94 ? 0 : 1) +
                         "A = " + std::to_string(ai) +
                         " acknowledges an element that is not in the FIFO");
        return true;
      }
      q.fill -= n;
      q.get = (ai + 1) % 3;
      return true;
    }
    case 0xCC: {
      for (unsigned i = 0; i < 3; ++i) {
        if (!((v >> i) & 1u) || (txbrp_ >> i) & 1u) continue;
        if (i != tx_put_ || tx_free_ == 0) {
          log_->Report(now_, "FDCAN1",
                       "TXBAR bit " + std::to_string(i) +
                           " is not the TX FIFO put index " + std::to_string(tx_put_) +
                           (tx_free_ == 0 ? " (FIFO full)" : "") + ": ignored");
          continue;
        }
        txbrp_ |= 1u << i;
        txbto_ &= ~(1u << i);
        txbcf_ &= ~(1u << i);
        tx_put_ = (tx_put_ + 1) % 3;
        --tx_free_;
      }
      TryStartTx();
      return true;
    }
    case 0xD0: {
      for (unsigned i = 0; i < 3; ++i) {
        if (!((v >> i) & 1u) || !((txbrp_ >> i) & 1u)) continue;
        if (static_cast<int>(i) == tx_current_ || i != tx_get_) {
          log_->Report(now_, "FDCAN1",
                       "cancellation of a TX element on the bus or not at "
                       "the FIFO head is not modelled");
          continue;
        }
        txbrp_ &= ~(1u << i);
        txbcf_ |= 1u << i;
        if (txbcie_ & (1u << i)) SetIr(kTcf);
        tx_get_ = (tx_get_ + 1) % 3;
        ++tx_free_;
      }
      return true;
    }
    case 0xE8: {
      const unsigned ai = v & 3u;
      const unsigned n = (ai + 3 - tx_event_.get) % 3 + 1;
      if (ai > 2 || tx_event_.fill == 0 || n > tx_event_.fill) {
        log_->Report(now_, "FDCAN1", "TXEFA acknowledges an element not in the FIFO");
        return true;
      }
      tx_event_.fill -= n;
      tx_event_.get = (ai + 1) % 3;
      return true;
    }
    default:
      break;
  }
  if (const char* name = ProtectedName(a.offset); name != nullptr && !Protected(name)) {
    return true;
  }
  if (a.offset == 0x10 && !(cccr_ & (1u << 7))) return true;  // TEST needs CCCR.TEST
  return WriteTableRegister(Registers(), *this, a);
}

bool Fdcan::ReadConfig(const Access& a, std::uint32_t* v) {
  if (a.offset != 0) return false;
  *v = ckdiv_;
  return true;
}

bool Fdcan::WriteConfig(const Access& a) {
  if (a.offset != 0) return false;
  if (Protected("FDCAN_CONFIG.CKDIV")) a.Apply(&ckdiv_, 0xFu);
  return true;
}

bool Fdcan::ReadRam(const Access& a, std::uint32_t* v) {
  if (a.offset >= kRamSize) return false;
  *v = ram_[a.offset / 4];
  return true;
}

bool Fdcan::WriteRam(const Access& a) {
  if (a.offset >= kRamSize) return false;
  a.Apply(&ram_[a.offset / 4]);
  return true;
}

}  // namespace mjc::g474model
