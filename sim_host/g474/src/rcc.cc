#include "mjc/g474model/rcc.h"

#include <cstdio>
#include <string>

namespace mjc::g474model {
namespace {

// RCC_CR bits (RM0440 RCC_CR; SVD v2.9).
constexpr std::uint32_t kHsion = 1u << 8, kHsikeron = 1u << 9, kHsirdy = 1u << 10;
constexpr std::uint32_t kHseon = 1u << 16, kHserdy = 1u << 17, kHsebyp = 1u << 18,
                        kCsson = 1u << 19;
constexpr std::uint32_t kPllon = 1u << 24, kPllrdy = 1u << 25;
// PLLCFGR fields that "can be written only when the PLL is disabled".
constexpr std::uint32_t kPllLockedFields = 0x3u | (0xFu << 4) | (0x7Fu << 8) |
                                           (1u << 17) | (3u << 21) | (3u << 25) |
                                           (0x1Fu << 27);
constexpr double kHsiHz = 16e6;

std::string Mhz(double hz) {
  char b[32];
  std::snprintf(b, sizeof b, "%.3f MHz", hz / 1e6);
  return b;
}

unsigned AhbDivider(std::uint32_t hpre) {
  if ((hpre & 0x8u) == 0) return 1;
  static constexpr unsigned kDiv[8] = {2, 4, 8, 16, 64, 128, 256, 512};
  return kDiv[hpre & 7u];
}
unsigned ApbDivider(std::uint32_t ppre) {
  if ((ppre & 0x4u) == 0) return 1;
  return 2u << (ppre & 3u);
}

}  // namespace

Rcc::Rcc(ViolationLog* log, const RccConfig& config) : log_(log), config_(config) {
  Reset();
  PowerOn();
}

void Rcc::PowerOn() { csr_ = csr::kBorrstf | csr::kPinrstf; }

void Rcc::Reset() {
  clocks_.valid = false;
  const std::uint32_t flags = csr_ & csr::kResetFlags;
  osc_ = {};
  // HSI16 runs after reset and is the system clock (CFGR reset value 0x5: SW = SWS =
  // HSI16). The SVD's RCC_CR reset value 0x63 names no field at bits 0/1/5/6 (it is
  // the STM32L4 value) and contradicts SWS = HSI16, which needs HSIRDY: HSION and
  // HSIRDY are set here (0x500).
  osc_[kHsi].on = osc_[kHsi].ready = true;
  cr_ = 0;
  icscr_ = 0x40000000u;
  cfgr_ = 0x00000005u;
  pllcfgr_ = 0x00001000u;
  cier_ = cifr_ = 0;
  ahb1rstr_ = ahb2rstr_ = ahb3rstr_ = apb1rstr1_ = apb1rstr2_ = apb2rstr_ = 0;
  ahb1enr_ = 0x00000100u;  // FLASHEN
  ahb2enr_ = ahb3enr_ = 0;
  apb1enr1_ = 0x00000400u;  // RTCAPBEN
  apb1enr2_ = apb2enr_ = 0;
  ahb1smenr_ = 0x0000130Fu;
  ahb2smenr_ = 0x050F667Fu;
  ahb3smenr_ = 0x00000101u;
  apb1smenr1_ = 0xD2FECD3Fu;
  apb1smenr2_ = 0x00000103u;
  apb2smenr_ = 0x0437F801u;
  ccipr_ = bdcr_ = crrcr_ = ccipr2_ = 0;
  csr_ = flags;  // LSION off, reset flags kept
}

void Rcc::Start(Osc o, Picoseconds delay) {
  if (osc_[o].on) return;
  clocks_.valid = false;
  osc_[o].on = true;
  osc_[o].ready = false;
  osc_[o].ready_at = delay == kNever ? kNever : now_ + delay;
}

void Rcc::Stop(Osc o) {
  osc_[o] = Oscillator{};
  clocks_.valid = false;
}

void Rcc::ForceLsiOn() {
  if (!osc_[kLsi].on) Start(kLsi, config_.lsi_startup);
}

double Rcc::PllInputHz() const {
  switch (pllcfgr_ & 3u) {
    case 2:
      return osc_[kHsi].ready ? kHsiHz : 0;
    case 3:
      return osc_[kHse].ready ? config_.hse_hz : 0;
    default:
      return 0;
  }
}

double Rcc::PllVcoHz() const {
  const double m = static_cast<double>(((pllcfgr_ >> 4) & 0xFu) + 1u);
  const double n = static_cast<double>((pllcfgr_ >> 8) & 0x7Fu);
  return PllInputHz() / m * n;
}

void Rcc::CheckPllConfig() {
  const double in = PllInputHz();
  if (in == 0) {
    log_->Report(now_, "RCC",
                 "PLLON set while the PLL's source (PLLCFGR.PLLSRC) is off or not ready: "
                 "the PLL cannot lock (RM0440 RCC 'PLL')");
    return;
  }
  const unsigned n = (pllcfgr_ >> 8) & 0x7Fu;
  const double vco_in = in / static_cast<double>(((pllcfgr_ >> 4) & 0xFu) + 1u);
  if (vco_in < 2.66e6 || vco_in > 16e6) {
    log_->Report(now_, "RCC",
                 "PLL VCO input " + Mhz(vco_in) +
                     " outside 2.66..16 MHz (DS12288 PLL characteristics)");
  }
  if (n < 8 || n > 127) {
    log_->Report(now_, "RCC",
                 "PLLN = " + std::to_string(n) + " is a wrong configuration (8..127)");
  }
  const double vco = PllVcoHz();
  if (vco < 64e6 || vco > 344e6) {
    log_->Report(now_, "RCC",
                 "PLL VCO output " + Mhz(vco) + " outside 64..344 MHz (DS12288)");
  }
  const double r = vco / (2.0 * static_cast<double>(((pllcfgr_ >> 25) & 3u) + 1u));
  if (r > 170e6) {
    log_->Report(now_, "RCC", "PLL R output " + Mhz(r) + " above 170 MHz");
  }
}

void Rcc::Advance(Picoseconds now) {
  now_ = now;
  bool changed = false;
  for (int o = 0; o < 4; ++o) {
    auto& x = osc_[static_cast<std::size_t>(o)];
    if (x.on && !x.ready && now >= x.ready_at) {
      // An HSE that is not fitted never becomes ready; a PLL whose input stopped
      // neither.
      if (o == kHse && config_.hse_hz <= 0) continue;
      if (o == kPll && PllInputHz() == 0) continue;
      x.ready = true;
      x.ready_at = kNever;
      changed = true;
      if (o == kLsi) csr_ |= csr::kLsirdy;
    }
  }
  const std::uint32_t before = cfgr_;
  UpdateSwitch();
  if (changed || before != cfgr_) Changed();
}

Picoseconds Rcc::NextEvent() const {
  Picoseconds next = kNever;
  for (const auto& x : osc_) {
    if (x.on && !x.ready && x.ready_at < next) next = x.ready_at;
  }
  return next;
}

void Rcc::UpdateSwitch() {
  const std::uint32_t sw = cfgr_ & 3u;
  const std::uint32_t sws = (cfgr_ >> 2) & 3u;
  if (sw == sws) return;
  bool ready = false;
  if (sw == 1) ready = osc_[kHsi].ready;
  if (sw == 2) ready = osc_[kHse].ready;
  if (sw == 3) ready = osc_[kPll].ready;
  if (!ready) return;  // the switch completes when the source is ready
  cfgr_ = (cfgr_ & ~(3u << 2)) | (sw << 2);
}

void Rcc::Changed() {
  clocks_.valid = false;
  if (change_hook_) change_hook_();
}

double Rcc::sysclk_hz_now() const {
  switch ((cfgr_ >> 2) & 3u) {
    case 1:
      return kHsiHz;
    case 2:
      return config_.hse_hz;
    case 3: {
      if (!osc_[kPll].ready || (pllcfgr_ & (1u << 24)) == 0) return 0;
      return PllVcoHz() / (2.0 * static_cast<double>(((pllcfgr_ >> 25) & 3u) + 1u));
    }
    default:
      return 0;
  }
}
double Rcc::hclk_hz_now() const {
  return sysclk_hz_now() / static_cast<double>(AhbDivider((cfgr_ >> 4) & 0xFu));
}
double Rcc::pclk1_hz_now() const {
  return hclk_hz_now() / static_cast<double>(ApbDivider((cfgr_ >> 8) & 7u));
}
double Rcc::pclk2_hz_now() const {
  return hclk_hz_now() / static_cast<double>(ApbDivider((cfgr_ >> 11) & 7u));
}
// RM0440 RCC clock tree: the timer clock is PCLK when the APB prescaler is 1, else
// twice PCLK.
double Rcc::tim_pclk1_hz_now() const {
  return ApbDivider((cfgr_ >> 8) & 7u) == 1 ? pclk1_hz_now() : 2 * pclk1_hz_now();
}
double Rcc::tim_pclk2_hz_now() const {
  return ApbDivider((cfgr_ >> 11) & 7u) == 1 ? pclk2_hz_now() : 2 * pclk2_hz_now();
}
double Rcc::pllq_hz_now() const {
  if (!osc_[kPll].ready || (pllcfgr_ & (1u << 20)) == 0) return 0;
  return PllVcoHz() / (2.0 * static_cast<double>(((pllcfgr_ >> 21) & 3u) + 1u));
}
double Rcc::fdcan_kernel_hz_now() const {
  switch ((ccipr_ >> 24) & 3u) {
    case 0:
      return osc_[kHse].ready ? config_.hse_hz : 0;
    case 1:
      return pllq_hz_now();
    case 2:
      return pclk1_hz_now();
    default:
      return 0;
  }
}

void Rcc::Recompute() const {
  clocks_.sysclk = sysclk_hz_now();
  clocks_.hclk = hclk_hz_now();
  clocks_.pclk1 = pclk1_hz_now();
  clocks_.pclk2 = pclk2_hz_now();
  clocks_.tim_pclk1 = tim_pclk1_hz_now();
  clocks_.tim_pclk2 = tim_pclk2_hz_now();
  clocks_.pllq = pllq_hz_now();
  clocks_.fdcan_kernel = fdcan_kernel_hz_now();
  clocks_.sysclk_whole = static_cast<std::uint64_t>(clocks_.sysclk);
  clocks_.tim_pclk1_whole = static_cast<std::uint64_t>(clocks_.tim_pclk1);
  clocks_.tim_pclk2_whole = static_cast<std::uint64_t>(clocks_.tim_pclk2);
  clocks_.valid = true;
}

bool Rcc::ClockEnabled(Gate g) const {
  switch (g) {
    case Gate::kFlash:
      return (ahb1enr_ & (1u << 8)) != 0;
    case Gate::kGpioA:
    case Gate::kGpioB:
    case Gate::kGpioC:
    case Gate::kGpioD:
    case Gate::kGpioE:
    case Gate::kGpioF:
    case Gate::kGpioG:
      return (ahb2enr_ >>
                  (static_cast<unsigned>(g) - static_cast<unsigned>(Gate::kGpioA)) &
              1u) != 0;
    case Gate::kTim3:
      return (apb1enr1_ & (1u << 1)) != 0;
    case Gate::kFdcan:
      return (apb1enr1_ & (1u << 25)) != 0;
    case Gate::kPwr:
      return (apb1enr1_ & (1u << 28)) != 0;
    case Gate::kTim1:
      return (apb2enr_ & (1u << 11)) != 0;
    case Gate::kSpi1:
      return (apb2enr_ & (1u << 12)) != 0;
    default:
      return false;
  }
}

RegisterTable<Rcc> Rcc::Registers() {
  using R = Register<Rcc>;
  // CR and CSR read and write through code of their own; CFGR, PLLCFGR and CICR (which
  // clears CIFR) write through it; the reset registers and CCIPR have side effects
  // after the write (see WriteRegister).
  static constexpr R kTable[] = {
      R::ReadWrite(0x04, &Rcc::icscr_, 0x7F000000u),
      R::ReadWrite(0x08, &Rcc::cfgr_),
      R::ReadWrite(0x0C, &Rcc::pllcfgr_),
      R::ReadWrite(0x18, &Rcc::cier_, 0x0000043Fu),
      R::ReadOnly(0x1C, &Rcc::cifr_),
      R::Fixed(0x20),
      R::ReadWrite(0x28, &Rcc::ahb1rstr_),
      R::ReadWrite(0x2C, &Rcc::ahb2rstr_),
      R::ReadWrite(0x30, &Rcc::ahb3rstr_),
      R::ReadWrite(0x38, &Rcc::apb1rstr1_),
      R::ReadWrite(0x3C, &Rcc::apb1rstr2_),
      R::ReadWrite(0x40, &Rcc::apb2rstr_),
      R::ReadWrite(0x48, &Rcc::ahb1enr_),
      R::ReadWrite(0x4C, &Rcc::ahb2enr_),
      R::ReadWrite(0x50, &Rcc::ahb3enr_),
      R::ReadWrite(0x58, &Rcc::apb1enr1_),
      R::ReadWrite(0x5C, &Rcc::apb1enr2_),
      R::ReadWrite(0x60, &Rcc::apb2enr_),
      R::ReadWrite(0x68, &Rcc::ahb1smenr_),
      R::ReadWrite(0x6C, &Rcc::ahb2smenr_),
      R::ReadWrite(0x70, &Rcc::ahb3smenr_),
      R::ReadWrite(0x78, &Rcc::apb1smenr1_),
      R::ReadWrite(0x7C, &Rcc::apb1smenr2_),
      R::ReadWrite(0x80, &Rcc::apb2smenr_),
      R::ReadWrite(0x88, &Rcc::ccipr_),
      R::ReadWrite(0x90, &Rcc::bdcr_),
      R::ReadWrite(0x98, &Rcc::crrcr_, 1u),
      R::ReadWrite(0x9C, &Rcc::ccipr2_),
  };
  return kTable;
}

bool Rcc::Read(const Access& a, std::uint32_t* v) {
  switch (a.offset) {
    case 0x00:
      *v = cr_ | (osc_[kHsi].on ? kHsion : 0) | (osc_[kHsi].ready ? kHsirdy : 0) |
           (osc_[kHse].on ? kHseon : 0) | (osc_[kHse].ready ? kHserdy : 0) |
           (osc_[kPll].on ? kPllon : 0) | (osc_[kPll].ready ? kPllrdy : 0);
      return true;
    case 0x94:
      *v = csr_ & ~csr::kRmvf;
      return true;
    default:
      return ReadTableRegister(Registers(), *this, a.offset, v);
  }
}

bool Rcc::Write(const Access& a) {
  const bool known = WriteRegister(a);
  clocks_.valid = false;
  return known;
}

bool Rcc::WriteRegister(const Access& a) {
  switch (a.offset) {
    case 0x00: {
      std::uint32_t current = 0;
      Read(a, &current);
      const std::uint32_t v = a.Merged(current);
      const std::uint32_t sws = (cfgr_ >> 2) & 3u;
      const std::uint32_t pllsrc = pllcfgr_ & 3u;
      // HSI16: "set by hardware if the HSI16 is used directly or indirectly as system
      // clock", so clearing it then has no effect.
      if (v & kHsion) {
        Start(kHsi, config_.hsi_startup);
      } else if (!(sws == 1 || (sws == 3 && pllsrc == 2))) {
        Stop(kHsi);
      }
      // HSEBYP "can be written only if the HSE oscillator is disabled".
      if (!osc_[kHse].on) {
        cr_ = (cr_ & ~kHsebyp) | (v & kHsebyp);
      } else if ((v & kHsebyp) != (cr_ & kHsebyp)) {
        log_->Report(now_, "RCC", "HSEBYP written while HSE is on: ignored");
      }
      if (v & kHseon) {
        Start(kHse, (cr_ & kHsebyp) ? Microseconds(1) : config_.hse_startup);
      } else if (sws == 2 || (sws == 3 && pllsrc == 3)) {
        log_->Report(now_, "RCC", "HSEON cleared while HSE clocks the system: ignored");
      } else {
        Stop(kHse);
      }
      if (v & kPllon) {
        if (!osc_[kPll].on) {
          CheckPllConfig();
          Start(kPll, config_.pll_lock);
        }
      } else if (sws == 3) {
        log_->Report(now_, "RCC",
                     "PLLON cleared while the PLL is the system clock: ignored");
      } else {
        Stop(kPll);
      }
      cr_ = (cr_ & ~kHsikeron) | (v & kHsikeron);
      cr_ |= v & kCsson;  // set only, cleared by reset
      Changed();
      return true;
    }
    case 0x08: {
      std::uint32_t v = a.Merged(cfgr_);
      if ((v & 3u) == 0) {
        log_->Report(now_, "RCC", "CFGR.SW = 00 is reserved: ignored");
        v = (v & ~3u) | (cfgr_ & 3u);
      }
      if ((v & 3u) == 3 && (pllcfgr_ & (1u << 24)) == 0) {
        log_->Report(now_, "RCC",
                     "SYSCLK switched to the PLL with PLLCFGR.PLLREN = 0: no clock on "
                     "PLLCLK");
      }
      cfgr_ = (v & ~(3u << 2) & 0x77F0FFF3u) | (cfgr_ & (3u << 2));
      UpdateSwitch();
      Changed();
      return true;
    }
    case 0x0C: {
      std::uint32_t v = a.Merged(pllcfgr_);
      if (osc_[kPll].on && ((v ^ pllcfgr_) & kPllLockedFields) != 0) {
        log_->Report(now_, "RCC",
                     "PLLCFGR source/divider fields written while PLLON = 1: ignored "
                     "(RM0440: 'can be written only when the PLL is disabled')");
        v = (v & ~kPllLockedFields) | (pllcfgr_ & kPllLockedFields);
      }
      if (((cfgr_ >> 2) & 3u) == 3 && ((v ^ pllcfgr_) & (1u << 24)) != 0) {
        log_->Report(now_, "RCC", "PLLREN written while PLLCLK is the system clock");
        v = (v & ~(1u << 24)) | (pllcfgr_ & (1u << 24));
      }
      pllcfgr_ = v & 0xFF737FF3u;
      Changed();
      return true;
    }
    case 0x20:
      cifr_ &= ~(a.value & a.mask & 0x0000073Fu);
      return true;
    case 0x94: {
      const std::uint32_t v = a.value & a.mask;
      if (v & csr::kRmvf) csr_ &= ~csr::kResetFlags;
      if (v & csr::kLsion) {
        csr_ |= csr::kLsion;
        ForceLsiOn();
      } else if (a.mask & csr::kLsion) {
        csr_ &= ~csr::kLsion;
      }
      return true;
    }
    default:
      break;
  }
  if (!WriteTableRegister(Registers(), *this, a)) return false;
  switch (a.offset) {
    case 0x2C:
      for (unsigned i = 0; i < 7; ++i) {
        if ((ahb2rstr_ >> i) & 1u && reset_hook_) {
          reset_hook_(static_cast<Gate>(static_cast<unsigned>(Gate::kGpioA) + i));
        }
      }
      break;
    case 0x38:
      if (reset_hook_) {
        if (apb1rstr1_ & (1u << 1)) reset_hook_(Gate::kTim3);
        if (apb1rstr1_ & (1u << 25)) reset_hook_(Gate::kFdcan);
        if (apb1rstr1_ & (1u << 28)) reset_hook_(Gate::kPwr);
      }
      break;
    case 0x40:
      if (reset_hook_) {
        if (apb2rstr_ & (1u << 11)) reset_hook_(Gate::kTim1);
        if (apb2rstr_ & (1u << 12)) reset_hook_(Gate::kSpi1);
      }
      break;
    case 0x88:
      Changed();
      break;
    default:
      break;
  }
  return true;
}

// ── PWR ────────────────────────────────────────────────────────────────────────────

Pwr::Pwr(ViolationLog* log) : log_(log) { Reset(); }

void Pwr::Reset() {
  cr1_ = 0x00000200u;  // VOS = 01: Range 1
  cr2_ = 0;
  cr3_ = 0x00008000u;
  cr4_ = sr1_ = 0;
  cr5_ = 0x00000100u;  // R1MODE = 1: Range 1 normal (no boost)
  pucr_pdcr_.fill(0);
  vosf_until_ = 0;
}

void Pwr::Advance(Picoseconds now) { now_ = now; }

RegisterTable<Pwr> Pwr::Registers() {
  using R = Register<Pwr>;
  // CR1 and CR5 have side effects after the write; SR2 reads through Read (VOSF).
  static constexpr R kTable[] = {
      R::ReadWrite(0x00, &Pwr::cr1_, 0x0000071Fu),
      R::ReadWrite(0x04, &Pwr::cr2_),
      R::ReadWrite(0x08, &Pwr::cr3_),
      R::ReadWrite(0x0C, &Pwr::cr4_),
      R::ReadOnly(0x10, &Pwr::sr1_),
      R::Fixed(0x14),
      R::Fixed(0x18),  // SCR reads 0
      R::ReadWrite(0x80, &Pwr::cr5_, 1u << 8),
  };
  return kTable;
}

std::uint32_t* Pwr::PullRegister(std::uint32_t offset) {
  // PUCRx/PDCRx of ports A..G, seven pairs from 0x20.
  if (offset >= 0x20 && offset <= 0x54) return &pucr_pdcr_[(offset - 0x20) / 4];
  return nullptr;
}

bool Pwr::Read(const Access& a, std::uint32_t* v) {
  // SR2.VOSF: "the regulator reached the voltage level defined with VOS" is shown
  // as 0; while it settles after a VOS change it reads 1 (REGLPF/REGLPS 0: the main
  // regulator runs).
  if (a.offset == 0x14) {
    *v = (now_ < vosf_until_) ? (1u << 10) : 0;
    return true;
  }
  if (const std::uint32_t* pull = PullRegister(a.offset)) {
    *v = *pull;
    return true;
  }
  return ReadTableRegister(Registers(), *this, a.offset, v);
}

bool Pwr::Write(const Access& a) {
  if (std::uint32_t* pull = PullRegister(a.offset)) {
    a.Apply(pull);
    return true;
  }
  const std::uint32_t old = cr1_;
  if (!WriteTableRegister(Registers(), *this, a)) return false;
  if (a.offset == 0x00) {
    const std::uint32_t vos = (cr1_ >> 9) & 3u;
    if (vos == 0 || vos == 3) {
      log_->Report(now_, "PWR", "CR1.VOS = " + std::to_string(vos) + " is reserved");
    }
    // The regulator needs time to settle after a range change (the datasheet's
    // tVOST, tens of µs): VOSF reads 1 meanwhile.
    if (((old ^ cr1_) >> 9 & 3u) != 0) vosf_until_ = now_ + Microseconds(20);
  }
  if ((a.offset == 0x00 || a.offset == 0x80) && change_hook_) change_hook_();
  return true;
}

// ── Clock rules ────────────────────────────────────────────────────────────────────

unsigned ClockRules::RequiredWaitStates(double hclk, int range, bool boost) {
  // FLASH "Number of wait states according to CPU clock (HCLK) frequency" table, as
  // ST's LL (stm32g4xx_ll_utils.c) encodes it.
  double step = 30e6;
  if (range == 2) {
    if (hclk <= 12e6) return 0;
    if (hclk <= 24e6) return 1;
    return 2;
  }
  if (boost) step = 34e6;
  unsigned ws = 0;
  while (hclk > step * (ws + 1) + 1) ++ws;
  return ws;
}

void ClockRules::Check(Picoseconds now, unsigned latency) {
  const double sysclk = rcc_->sysclk_hz();
  const double hclk = rcc_->hclk_hz();
  const int range = pwr_->voltage_range();
  const bool boost = pwr_->boost();
  const double limit = range == 2 ? 26e6 : (boost ? 170e6 : 150e6);
  if (sysclk > limit + 1) {
    log_->Report(now, "RCC",
                 "SYSCLK " + Mhz(sysclk) + " above the " + Mhz(limit) + " the present " +
                     (range == 2 ? std::string("Range 2")
                      : boost    ? std::string("Range 1 boost")
                                 : std::string("Range 1 normal (PWR_CR5.R1MODE = 1)")) +
                     " allows (RM0440 PWR 'Dynamic voltage scaling management')");
  }
  const unsigned need = RequiredWaitStates(hclk, range, boost);
  if (latency < need) {
    log_->Report(now, "FLASH",
                 "HCLK " + Mhz(hclk) + " needs " + std::to_string(need) +
                     " wait states, FLASH_ACR.LATENCY = " + std::to_string(latency) +
                     " (RM0440 FLASH 'Read access latency': raise LATENCY before the "
                     "clock)");
  }
  const unsigned hpre_div = AhbDivider((rcc_->cfgr() >> 4) & 0xFu);
  if (sysclk > 80e6 && last_sysclk_ <= 80e6) {
    above80_since_ = now;
    if (hpre_div == 1) {
      log_->Report(now, "RCC",
                   "SYSCLK switched from " + Mhz(last_sysclk_) + " to " + Mhz(sysclk) +
                       " with the AHB prescaler at /1: set HPRE = /2 for the switch and "
                       "back to /1 after >= 1 us (RM0440 RCC, as ST's HAL applies it)");
    }
  }
  if (sysclk > 80e6 && hpre_div == 1 && last_hpre_div_ > 1 && above80_since_ != kNever &&
      now - above80_since_ < Microseconds(1)) {
    log_->Report(now, "RCC",
                 "AHB prescaler back to /1 only " +
                     std::to_string((now - above80_since_) / 1000) +
                     " ns after SYSCLK crossed 80 MHz (>= 1 us required)");
  }
  last_sysclk_ = sysclk;
  last_hpre_div_ = hpre_div;
}

}  // namespace mjc::g474model
