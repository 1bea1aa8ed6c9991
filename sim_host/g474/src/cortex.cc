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
// MPU (B3.5.5 - B3.5.9).
constexpr std::uint32_t kMpuType = 0xED90, kMpuCtrl = 0xED94, kMpuRnr = 0xED98,
                        kMpuRbar = 0xED9C, kMpuRasr = 0xEDA0;
// RASR: XN, AP, TEX, S, C, B, SRD, SIZE, ENABLE.
constexpr std::uint32_t kRasrBits = 0x173FFF3Fu;
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
  mpu_ctrl_ = mpu_rnr_ = 0;
  mpu_rbar_.fill(0);
  mpu_rasr_.fill(0);
}

std::optional<int> Cortex::MpuDenies(std::uint32_t address, bool write) const {
  if (!mpu_enabled() || (address >= 0xE0000000u && address < 0xE0100000u)) {
    return std::nullopt;
  }
  for (int r = kMpuRegions - 1; r >= 0; --r) {
    const std::uint32_t rasr = mpu_rasr_[static_cast<std::size_t>(r)];
    if (!(rasr & 1u)) continue;
    const unsigned size_log2 = ((rasr >> 1) & 0x1Fu) + 1;
    const std::uint64_t size = std::uint64_t{1} << size_log2;
    const std::uint64_t base = mpu_rbar_[static_cast<std::size_t>(r)] & ~(size - 1);
    if (address < base || address >= base + size) continue;
    // Eight subregions in regions of 256 bytes or more; a disabled one is not part of
    // the region (the next lower region, or the background, decides there).
    if (size >= 256 && ((rasr >> 8) >> ((address - base) / (size / 8)) & 1u)) continue;
    const unsigned ap = (rasr >> 24) & 7u;
    if (ap == 0 || ap == 4) return r;  // no access (100 is reserved)
    if (write && ap >= 5) return r;    // read-only for privileged code
    return std::nullopt;
  }
  if (mpu_ctrl_ & 4u) return std::nullopt;  // PRIVDEFENA: the default map
  return -1;
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
    case kMpuType:
      *v = static_cast<std::uint32_t>(kMpuRegions) << 8;  // DREGION; SEPARATE = 0
      return true;
    case kMpuCtrl:
      *v = mpu_ctrl_;
      return true;
    case kMpuRnr:
      *v = mpu_rnr_;
      return true;
    case kMpuRbar:
      *v = (mpu_rbar_[mpu_rnr_ % kMpuRegions] & ~0x1Fu) | (mpu_rnr_ & 0xFu);
      return true;
    case kMpuRasr:
      *v = mpu_rasr_[mpu_rnr_ % kMpuRegions];
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
    case kMpuType:
      return true;  // read-only
    case kMpuCtrl:
      a.Apply(&mpu_ctrl_, 7u);
      return true;
    case kMpuRnr:
      if ((v & 0xFFu) >= kMpuRegions) {
        log_->Report(now_, "MPU",
                     "MPU_RNR = " + std::to_string(v & 0xFFu) + ": only 8 regions");
      }
      mpu_rnr_ = (v & 0xFFu) % kMpuRegions;
      return true;
    case kMpuRbar:
      if (v & 0x10u) mpu_rnr_ = v & 0xFu & (kMpuRegions - 1);  // VALID: REGION selects
      mpu_rbar_[mpu_rnr_] = v & ~0x1Fu;
      return true;
    case kMpuRasr: {
      const std::uint32_t rasr = v & kRasrBits;
      mpu_rasr_[mpu_rnr_] = rasr;
      const unsigned size_field = (rasr >> 1) & 0x1Fu;
      if ((rasr & 1u) && size_field < 4) {
        log_->Report(now_, "MPU",
                     "region " + std::to_string(mpu_rnr_) +
                         " enabled with SIZE < 4 (under 32 bytes): "
                         "UNPREDICTABLE (ARMv7-M B3.5.9)");
      } else if ((rasr & 1u) && size_field < 31 &&
                 (mpu_rbar_[mpu_rnr_] & ((2u << size_field) - 1u)) != 0) {
        log_->Report(now_, "MPU",
                     "region " + std::to_string(mpu_rnr_) + " base " +
                         Hex(mpu_rbar_[mpu_rnr_]) +
                         " not aligned to its size: UNPREDICTABLE");
      }
      return true;
    }
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
