#include "mjc/g474model/cortex.h"

#include <string>

namespace mjc::g474model {
namespace {
// Offsets from 0xE0000000 (ARMv7-M ARM B3.2.2, B3.4.3, C1.8.7, C1.6.5).
constexpr std::uint32_t kDwtCtrl = 0x1000;
constexpr std::uint32_t kIser = 0xE100, kIcer = 0xE180, kIspr = 0xE200, kIcpr = 0xE280,
                        kIabr = 0xE300, kIpr = 0xE400, kStir = 0xEF00;
constexpr std::uint32_t kCpuid = 0xED00, kIcsr = 0xED04, kVtor = 0xED08, kAircr = 0xED0C,
                        kScr = 0xED10, kCcr = 0xED14, kShpr1 = 0xED18, kShcsr = 0xED24,
                        kCfsr = 0xED28, kHfsr = 0xED2C, kCpacr = 0xED88, kDemcr = 0xEDFC;
// Cortex-M4 r0p1 (the STM32G4's core, ST's CMSIS header: __CM4_REV 0x0001).
constexpr std::uint32_t kCpuidValue = 0x410FC241u;
}  // namespace

void Cortex::Reset() {
  enabled_.reset();
  pending_.reset();
  active_.reset();
  priority_.fill(0);
  vtor_ = 0;
  aircr_ = 0;
  scr_ = 0;
  ccr_ = 0x00000200u;  // STKALIGN
  cpacr_ = 0;
  shpr_.fill(0);
  dwt_ctrl_ = 0x40000000u;  // NUMCOMP = 4
  demcr_ = 0;
  cyccnt_base_ = 0;
  cyccnt_origin_ = *cycles_;
}

std::uint32_t Cortex::Cyccnt() const {
  if (!cyccnt_running()) return cyccnt_base_;
  return cyccnt_base_ + static_cast<std::uint32_t>(*cycles_ - cyccnt_origin_);
}

RegisterTable<Cortex> Cortex::Registers() {
  using R = Register<Cortex>;
  // DWT_CTRL, ICSR, VTOR and DEMCR write through code of their own (see Write), CYCCNT,
  // AIRCR and the SHPRs read and write through it.
  static constexpr R kTable[] = {
      R::ReadWrite(kDwtCtrl, &Cortex::dwt_ctrl_),
      R::Fixed(kCpuid, kCpuidValue),
      R::Fixed(kIcsr),
      R::ReadWrite(kVtor, &Cortex::vtor_),
      R::ReadWrite(kScr, &Cortex::scr_, 0x16u),
      R::ReadWrite(kCcr, &Cortex::ccr_, 0x31Bu),
      R::Fixed(kShcsr),  // no fault handlers modelled: the fault status reads 0
      R::Fixed(kCfsr),
      R::Fixed(kHfsr),
      R::ReadWrite(kCpacr, &Cortex::cpacr_, 0x00F00000u),
      R::ReadWrite(kDemcr, &Cortex::demcr_, 0x010F07F1u),
  };
  return kTable;
}

bool Cortex::Read(const Access& a, std::uint32_t* v) {
  const std::uint32_t o = a.offset;
  auto bank = [&](std::uint32_t base, const std::bitset<kIrqCount>& bits) {
    const std::uint32_t word = (o - base) / 4;
    std::uint32_t r = 0;
    for (std::uint32_t i = 0; i < 32; ++i) {
      const std::uint32_t irq = word * 32 + i;
      if (irq < kIrqCount && bits[irq]) r |= 1u << i;
    }
    return r;
  };
  if (o >= kIser && o < kIser + 32) return *v = bank(kIser, enabled_), true;
  if (o >= kIcer && o < kIcer + 32) return *v = bank(kIcer, enabled_), true;
  if (o >= kIspr && o < kIspr + 32) return *v = bank(kIspr, pending_), true;
  if (o >= kIcpr && o < kIcpr + 32) return *v = bank(kIcpr, pending_), true;
  if (o >= kIabr && o < kIabr + 32) return *v = bank(kIabr, active_), true;
  if (o >= kIpr && o < kIpr + 0xF0) {
    std::uint32_t r = 0;
    for (std::uint32_t i = 0; i < 4; ++i) {
      const std::uint32_t irq = o - kIpr + i;
      if (irq < kIrqCount) r |= static_cast<std::uint32_t>(priority_[irq]) << (8 * i);
    }
    *v = r;
    return true;
  }
  switch (o) {
    case kDwtCyccnt:
      *v = Cyccnt();
      return true;
    case kAircr:
      *v = 0xFA050000u | (aircr_ & 0x8700u);
      return true;
    case kShpr1:
    case kShpr1 + 4:
    case kShpr1 + 8:
      *v = shpr_[(o - kShpr1) / 4];
      return true;
    default:
      return ReadTableRegister(Registers(), *this, o, v);
  }
}

bool Cortex::Write(const Access& a) {
  const std::uint32_t o = a.offset;
  const std::uint32_t v = a.value & a.mask;
  auto apply = [&](std::uint32_t base, std::bitset<kIrqCount>* bits, bool set) {
    const std::uint32_t word = (o - base) / 4;
    for (std::uint32_t i = 0; i < 32; ++i) {
      const std::uint32_t irq = word * 32 + i;
      if (irq < kIrqCount && ((v >> i) & 1u)) (*bits)[irq] = set;
    }
    return true;
  };
  if (o >= kIser && o < kIser + 32) return apply(kIser, &enabled_, true);
  if (o >= kIcer && o < kIcer + 32) return apply(kIcer, &enabled_, false);
  if (o >= kIspr && o < kIspr + 32) return apply(kIspr, &pending_, true);
  if (o >= kIcpr && o < kIcpr + 32) return apply(kIcpr, &pending_, false);
  if (o >= kIabr && o < kIabr + 32) return true;  // read-only
  if (o >= kIpr && o < kIpr + 0xF0) {
    for (std::uint32_t i = 0; i < 4; ++i) {
      const std::uint32_t irq = o - kIpr + i;
      if (irq < kIrqCount && ((a.mask >> (8 * i)) & 0xFFu)) {
        // Only the 4 most significant bits exist (__NVIC_PRIO_BITS = 4).
        priority_[irq] = static_cast<std::uint8_t>((a.value >> (8 * i)) & 0xF0u);
      }
    }
    return true;
  }
  switch (o) {
    case kStir:
      if ((v & 0x1FFu) < kIrqCount) pending_[v & 0x1FFu] = true;
      return true;
    case kDwtCtrl: {
      if ((demcr_ & (1u << 24)) == 0) {
        log_->Report(now_, "DWT",
                     "DWT_CTRL written with DEMCR.TRCENA = 0: the DWT is disabled "
                     "(ARMv7-M ARM C1.6.5), CYCCNT will not count");
        return true;
      }
      const std::uint32_t count = Cyccnt();
      dwt_ctrl_ = (dwt_ctrl_ & 0xF0000000u) | (a.Merged(dwt_ctrl_) & 0x0FFFFFFFu);
      cyccnt_base_ = count;
      cyccnt_origin_ = *cycles_;
      return true;
    }
    case kDwtCyccnt:
      if ((demcr_ & (1u << 24)) == 0) {
        log_->Report(now_, "DWT", "DWT_CYCCNT written with DEMCR.TRCENA = 0: ignored");
        return true;
      }
      cyccnt_base_ = a.Merged(Cyccnt());
      cyccnt_origin_ = *cycles_;
      return true;
    case kIcsr: {
      if (v & (1u << 28))
        log_->Report(now_, "SCB", "ICSR.PENDSVSET: PendSV not modelled");
      return true;
    }
    case kVtor: {
      const std::uint32_t t = a.Merged(vtor_) & 0xFFFFFF80u;
      // 16 + 102 vectors = 118 words: the table must be aligned to 512 bytes (the
      // next power of two, ARMv7-M ARM B3.2.5).
      if (t & 0x1FFu) {
        log_->Report(now_, "SCB",
                     "VTOR 0x" + std::to_string(t) +
                         " is not 512-byte aligned (118 vectors, ARMv7-M ARM B3.2.5)");
      }
      vtor_ = t;
      return true;
    }
    case kAircr: {
      const std::uint32_t w = a.Merged(0xFA050000u | aircr_);
      if ((w >> 16) != 0x05FAu) {
        log_->Report(
            now_, "SCB",
            "AIRCR written without VECTKEY 0x05FA: ignored (ARMv7-M ARM B3.2.6)");
        return true;
      }
      aircr_ = w & 0x0700u;
      if (w & (1u << 2)) {
        if (reset_hook_) reset_hook_();
      }
      return true;
    }
    case kShpr1:
    case kShpr1 + 4:
    case kShpr1 + 8:
      a.Apply(&shpr_[(o - kShpr1) / 4], 0xF0F0F0F0u);
      return true;
    case kCpuid:
      return false;  // the model takes no write here: the bus reports a reserved register
    case kDemcr: {
      const std::uint32_t count = Cyccnt();
      WriteTableRegister(Registers(), *this, a);
      cyccnt_base_ = count;
      cyccnt_origin_ = *cycles_;
      return true;
    }
    default:
      return WriteTableRegister(Registers(), *this, a);
  }
}

}  // namespace mjc::g474model
