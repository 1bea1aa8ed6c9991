#include "mjc/g474model/timer.h"

#include <algorithm>
#include <string>

namespace mjc::g474model {
namespace {
constexpr std::uint32_t kCen = 1u << 0, kUdis = 1u << 1, kUrs = 1u << 2, kArpe = 1u << 7;
constexpr std::uint32_t kMoe = 1u << 15, kOssi = 1u << 10, kOssr = 1u << 11;

std::uint32_t CcmrOf(int ch, std::uint32_t ccmr1, std::uint32_t ccmr2) {
  return ch <= 2 ? ccmr1 : ccmr2;
}
int Slot(int ch) { return (ch - 1) % 2; }  // 0 = low half of CCMRx, 1 = high half
}  // namespace

Timer::Timer(Kind kind, const char* name, ViolationLog* log, const Rcc* rcc)
    : kind_(kind), name_(name), log_(log), rcc_(rcc) {
  Reset();
}

void Timer::Reset() {
  cr1_ = cr2_ = smcr_ = dier_ = sr_ = ccmr1_ = ccmr2_ = ccer_ = psc_ = rcr_ = bdtr_ =
      ccmr3_ = dtr2_ = ecr_ = tisel_ = dcr_ = 0;
  // AF1/AF2 reset values per the SVD (TIM1: 0x1, BKINE set; TIM3: 0).
  af1_ = af2_ = kind_ == Kind::kAdvanced ? 1u : 0u;
  arr_ = 0xFFFF;
  ccr_.fill(0);
  cnt_ = psc_count_ = psc_active_ = rep_ = rcr_active_ = 0;
  arr_active_ = 0xFFFF;
  ccr_active_.fill(0);
  down_ = false;
  clock_.Reset();
  reported_mode_ = false;
}

double Timer::kernel_hz() const {
  return kind_ == Kind::kAdvanced ? rcc_->tim_pclk2_hz() : rcc_->tim_pclk1_hz();
}

bool Timer::EncoderMode() const {
  const unsigned s = Sms();
  return s == 1 || s == 2 || s == 3 || s == 14 || s == 15;
}

void Timer::LoadShadows() {
  arr_active_ = arr_;
  psc_active_ = psc_;
  rcr_active_ = rcr_;
  for (int ch = 1; ch <= 4; ++ch)
    ccr_active_[static_cast<std::size_t>(ch - 1)] =
        ccr_[static_cast<std::size_t>(ch - 1)];
}

void Timer::CountEvent() {
  if (cr1_ & kUdis) return;
  if (rep_ > 0) {
    --rep_;
    return;
  }
  rep_ = rcr_active_ = rcr_;
  // At the update event the preloaded registers take their new values (without
  // preload they already act immediately: see Write).
  arr_active_ = arr_;
  psc_active_ = psc_;
  for (std::size_t i = 0; i < 4; ++i) ccr_active_[i] = ccr_[i];
  sr_ |= 1u;  // UIF
}

void Timer::Tick(std::uint64_t n) {
  const std::uint32_t arr = arr_active_;
  while (n > 0) {
    if (Cms() == 0) {
      if (!CountingDown()) {
        const std::uint64_t to_ovf = cnt_ <= arr ? arr - cnt_ + 1 : 0x10000u - cnt_;
        if (n < to_ovf) {
          cnt_ += static_cast<std::uint32_t>(n);
          return;
        }
        n -= to_ovf;
        const bool was_above = cnt_ > arr;
        cnt_ = 0;
        if (!was_above) CountEvent();
      } else {
        const std::uint64_t to_unf = static_cast<std::uint64_t>(cnt_) + 1;
        if (n < to_unf) {
          cnt_ -= static_cast<std::uint32_t>(n);
          return;
        }
        n -= to_unf;
        cnt_ = arr_active_;
        CountEvent();
      }
    } else {
      if (arr == 0) return;  // the counter does not count with ARR = 0
      if (!down_) {
        const std::uint64_t to_top = cnt_ < arr ? arr - cnt_ : 0;
        if (n < to_top) {
          cnt_ += static_cast<std::uint32_t>(n);
          return;
        }
        n -= to_top;
        cnt_ = arr;
        down_ = true;
        CountEvent();
        if (to_top == 0 && n > 0) {
          --n;
          cnt_ = arr - 1;
        }
      } else {
        const std::uint64_t to_bottom = cnt_;
        if (n < to_bottom) {
          cnt_ -= static_cast<std::uint32_t>(n);
          return;
        }
        n -= to_bottom;
        cnt_ = 0;
        down_ = false;
        CountEvent();
        if (to_bottom == 0 && n > 0) {
          --n;
          cnt_ = 1;
        }
      }
    }
    // Guard against a zero-length loop (to_ovf/to_top are never 0 for arr > 0 here).
  }
}

void Timer::Advance(Picoseconds now) {
  const Picoseconds dt = now - now_;
  now_ = now;
  const std::uint64_t hz = !clock_on_ || debug_stopped_ ? 0
                           : kind_ == Kind::kAdvanced   ? rcc_->tim_pclk2_whole_hz()
                                                        : rcc_->tim_pclk1_whole_hz();
  const std::uint64_t clocks = clock_.Advance(dt, hz);
  if (!(cr1_ & kCen) || EncoderMode() || Sms() != 0) {
    return;
  }
  // Prescaler: one counter tick per PSC+1 kernel clocks.
  const std::uint64_t div = static_cast<std::uint64_t>(psc_active_) + 1;
  const std::uint64_t total = psc_count_ + clocks;
  psc_count_ = static_cast<std::uint32_t>(total % div);
  Tick(total / div);
}

std::uint64_t Timer::TicksToNextUpdate() const {
  const std::uint64_t arr = arr_active_;
  std::uint64_t first = 0, half = 0;
  if (Cms() == 0) {
    half = arr + 1;
    first = CountingDown() ? cnt_ + 1u : (cnt_ <= arr ? arr - cnt_ + 1 : 0x10000u - cnt_);
  } else {
    if (arr == 0) return 0;
    half = arr;
    first = down_ ? cnt_ : arr - cnt_;
    if (first == 0) first = half;
  }
  return first + half * rep_;
}

Picoseconds Timer::NextEvent() const {
  if (!(dier_ & 1u) || (sr_ & 1u)) return kNever;  // no new interrupt to raise
  return NextUpdate();
}

Picoseconds Timer::NextUpdate() const {
  if (!clock_on_ || debug_stopped_ || !(cr1_ & kCen) || Sms() != 0 || (cr1_ & kUdis)) {
    return kNever;
  }
  const std::uint64_t ticks = TicksToNextUpdate();
  if (ticks == 0) return kNever;
  const std::uint64_t div = static_cast<std::uint64_t>(psc_active_) + 1;
  const std::uint64_t clocks = (ticks - 1) * div + (div - psc_count_);
  const Picoseconds dt =
      clock_.UntilTicks(clocks, kind_ == Kind::kAdvanced ? rcc_->tim_pclk2_whole_hz()
                                                         : rcc_->tim_pclk1_whole_hz());
  return dt == kNever ? kNever : now_ + dt;
}

double Timer::UpdatePeriodSeconds() const {
  const double hz = kernel_hz();
  if (hz <= 0) return 0;
  const double ticks = Cms() == 0 ? static_cast<double>(arr_active_) + 1
                                  : static_cast<double>(arr_active_);
  return ticks * (static_cast<double>(psc_active_) + 1) *
         (static_cast<double>(rcr_active_) + 1) / hz;
}

void Timer::EncoderStep(int delta) {
  if (delta > 0) {
    if (cnt_ >= arr_active_) {
      cnt_ = 0;
      CountEvent();
    } else {
      ++cnt_;
    }
  } else {
    if (cnt_ == 0) {
      cnt_ = arr_active_;
      CountEvent();
    } else {
      --cnt_;
    }
  }
}

void Timer::OnInput(int channel, bool level) {
  const std::size_t i = static_cast<std::size_t>(channel - 1);
  if (input_[i] == level) return;
  input_[i] = level;
  if (channel > 2 || !(cr1_ & kCen) || !EncoderMode() || debug_stopped_) return;
  // TIxFPx: the input after the polarity selection (CCxP inverts).
  const bool ti1 = input_[0] != ((ccer_ >> 1) & 1u);
  const bool ti2 = input_[1] != ((ccer_ >> 5) & 1u);
  const bool rising = channel == 1 ? ti1 : ti2;
  const unsigned sms = Sms();
  int delta = 0;
  // RM0440 "Counting direction versus encoder signals": on a TI1FP1 edge the direction
  // comes from TI2FP2's level and vice versa; a forward quadrature sequence counts up.
  if (channel == 1 && (sms == 1 || sms == 3)) delta = (rising != ti2) ? +1 : -1;
  if (channel == 2 && (sms == 2 || sms == 3)) delta = (rising == ti1) ? +1 : -1;
  // x1 modes: one count per cycle, on the TI1 (1110) or TI2 (1111) edge where the
  // other input is low; an assumption that keeps forward and backward crossings of the
  // same edge symmetric.
  if (sms == 14 && channel == 1 && !ti2) delta = rising ? +1 : -1;
  if (sms == 15 && channel == 2 && ti1) delta = rising ? +1 : -1;
  if (delta != 0) EncoderStep(delta);
}

unsigned Timer::OcMode(int ch) const {
  const std::uint32_t m = CcmrOf(ch, ccmr1_, ccmr2_);
  const int s = Slot(ch);
  return ((m >> (4 + 8 * s)) & 7u) | (((m >> (16 + 8 * s)) & 1u) << 3);
}

bool Timer::RefActiveNow(int ch) const {
  const std::uint32_t ccr = ccr_active_[static_cast<std::size_t>(ch - 1)];
  switch (OcMode(ch)) {
    case 4:
      return false;
    case 5:
      return true;
    case 6:
    case 7: {
      bool active;
      if (Cms() == 0 && CountingDown()) {
        active = cnt_ <= ccr;
      } else if (Cms() != 0 && down_) {
        active = cnt_ <= ccr;
      } else {
        active = cnt_ < ccr;
      }
      return OcMode(ch) == 6 ? active : !active;
    }
    default:
      return false;
  }
}

double Timer::RefDuty(int ch) const {
  const double ccr = static_cast<double>(ccr_active_[static_cast<std::size_t>(ch - 1)]);
  const double arr = static_cast<double>(arr_active_);
  double d = 0;
  switch (OcMode(ch)) {
    case 5:
      return 1;
    case 6:
    case 7:
      if (Cms() == 0) {
        // Up: active while CNT < CCR over ARR+1 ticks; down: while CNT <= CCR.
        d = CountingDown() ? (ccr + 1) / (arr + 1) : ccr / (arr + 1);
      } else {
        // Centre-aligned: CCR ticks active on the way up and down, of 2·ARR.
        d = arr > 0 ? ccr / arr : 0;
      }
      d = std::clamp(d, 0.0, 1.0);
      return OcMode(ch) == 6 ? d : 1 - d;
    default:
      return RefActiveNow(ch) ? 1 : 0;
  }
}

double Timer::DeadTimeSeconds() const {
  const double hz = kernel_hz();
  if (hz <= 0 || kind_ != Kind::kAdvanced) return 0;
  const unsigned ckd = (cr1_ >> 8) & 3u;
  const double tdts = static_cast<double>(1u << (ckd > 2 ? 2 : ckd)) / hz;
  const unsigned dtg = bdtr_ & 0xFFu;
  double steps;
  if ((dtg & 0x80u) == 0) {
    steps = dtg;
  } else if ((dtg & 0xC0u) == 0x80u) {
    steps = (64.0 + (dtg & 0x3Fu)) * 2;
  } else if ((dtg & 0xE0u) == 0xC0u) {
    steps = (32.0 + (dtg & 0x1Fu)) * 8;
  } else {
    steps = (32.0 + (dtg & 0x1Fu)) * 16;
  }
  return steps * tdts;
}

double Timer::PeriodSeconds() const {
  const double hz = kernel_hz();
  if (hz <= 0) return 0;
  const double ticks = Cms() == 0 ? static_cast<double>(arr_active_) + 1
                                  : 2.0 * static_cast<double>(arr_active_);
  return ticks * (static_cast<double>(psc_active_) + 1) / hz;
}

OutputWave Timer::Wave(int ch, bool complementary) const {
  const unsigned shift = 4u * static_cast<unsigned>(ch - 1);
  const bool cce = (ccer_ >> shift) & 1u, ccp = (ccer_ >> (shift + 1)) & 1u;
  const bool ccne = (ccer_ >> (shift + 2)) & 1u, ccnp = (ccer_ >> (shift + 3)) & 1u;
  const bool pol = complementary ? ccnp : ccp;
  auto level = [&](double high_fraction) {
    return OutputWave{true, pol ? 1 - high_fraction : high_fraction};
  };
  if (kind_ != Kind::kAdvanced) {
    if (complementary || !cce) return {};
    return level(RefDuty(ch));
  }
  if (!(bdtr_ & kMoe) || debug_stopped_) {
    // Main output disabled (or the counter frozen by the debugger, which disables the
    // outputs as a cleared MOE does): Hi-Z with OSSI = 0, else the idle level
    // OISx/OISxN.
    if (!(bdtr_ & kOssi) || !(cce || ccne)) return {};
    const bool ois = (cr2_ >> (8 + 2 * (ch - 1) + (complementary ? 1 : 0))) & 1u;
    return OutputWave{true, ois ? 1.0 : 0.0};
  }
  const bool enabled = complementary ? ccne : cce;
  if (!enabled) {
    // Off-state in run mode: Hi-Z with OSSR = 0, inactive level with OSSR = 1 (when
    // the other output of the pair is enabled).
    if ((bdtr_ & kOssr) && (cce || ccne)) return level(0);
    return {};
  }
  const double ref = RefDuty(ch);
  if (cce && ccne) {
    // Complementary pair: each output's active phase starts one dead time after the
    // reference edge (only where the reference has edges).
    const double period = PeriodSeconds();
    const double dt = period > 0 ? DeadTimeSeconds() / period : 0;
    if (ref <= 0 || ref >= 1) return level(complementary ? 1 - ref : ref);
    const double active = complementary ? 1 - ref : ref;
    return level(std::max(0.0, active - dt));
  }
  // Only one of the pair enabled: it follows OCxREF (OCxN too, not inverted).
  return level(ref);
}

Drive Timer::Level(int ch, bool complementary) const {
  const OutputWave w = Wave(ch, complementary);
  if (!w.driven) return Drive::kHighZ;
  if (w.duty <= 0) return Drive::kLow;
  if (w.duty >= 1) return Drive::kHigh;
  // A PWM output: its instantaneous level from the reference now (dead time ignored
  // for the instant).
  const unsigned shift = 4u * static_cast<unsigned>(ch - 1);
  bool ref = RefActiveNow(ch);
  const bool both = ((ccer_ >> shift) & 1u) && ((ccer_ >> (shift + 2)) & 1u);
  if (complementary && both) ref = !ref;
  const bool pol = (ccer_ >> (shift + (complementary ? 3 : 1))) & 1u;
  return (ref != pol) ? Drive::kHigh : Drive::kLow;
}

RegisterTable<Timer> Timer::Registers() {
  using R = Register<Timer>;
  // CR1, SMCR, CCMRx and ARR have side effects after the write (see Write), EGR and the
  // CCRx have code of their own; CCER's writable bits are TIM3's (TIM1's in Write).
  static constexpr R kTable[] = {
      R::ReadWrite(0x00, &Timer::cr1_, 0x1BFFu),
      R::ReadWrite(0x04, &Timer::cr2_),
      R::ReadWrite(0x08, &Timer::smcr_),
      R::ReadWrite(0x0C, &Timer::dier_),
      R::ClearByWriting0(0x10, &Timer::sr_),
      R::Fixed(0x14),  // EGR reads 0
      R::ReadWrite(0x18, &Timer::ccmr1_),
      R::ReadWrite(0x1C, &Timer::ccmr2_),
      R::ReadWrite(0x20, &Timer::ccer_, 0x0000BBBBu),
      R::ReadWrite(0x24, &Timer::cnt_, 0xFFFFu),
      R::ReadWrite(0x28, &Timer::psc_, 0xFFFFu),  // always preloaded
      R::ReadWrite(0x2C, &Timer::arr_, 0xFFFFu),
      R::ReadWrite(0x58, &Timer::ecr_),
      R::ReadWrite(0x5C, &Timer::tisel_),
      R::ReadWrite(0x60, &Timer::af1_),
      R::ReadWrite(0x64, &Timer::af2_),
      R::ReadWrite(0x3DC, &Timer::dcr_),
      R::Fixed(0x3E0),
  };
  return kTable;
}

RegisterTable<Timer> Timer::AdvancedRegisters() {
  using R = Register<Timer>;
  // LOCK levels are not modelled; BDTR.MOE is what gates the outputs.
  static constexpr R kTable[] = {
      R::ReadWrite(0x30, &Timer::rcr_, 0xFFFFu), R::ReadWrite(0x44, &Timer::bdtr_),
      R::ReadWrite(0x50, &Timer::ccmr3_), R::ReadWrite(0x54, &Timer::dtr2_)};
  return kTable;
}

std::uint32_t* Timer::Ccr(std::uint32_t offset) {
  if (offset >= 0x34 && offset <= 0x40) return &ccr_[(offset - 0x34) / 4];
  if (kind_ != Kind::kAdvanced) return nullptr;
  if (offset == 0x48) return &ccr_[4];
  if (offset == 0x4C) return &ccr_[5];
  return nullptr;
}

bool Timer::Read(const Access& a, std::uint32_t* v) {
  if (const std::uint32_t* ccr = Ccr(a.offset)) {
    *v = *ccr;
    return true;
  }
  return ReadTableRegister(Registers(), *this, a.offset, v) ||
         (kind_ == Kind::kAdvanced &&
          ReadTableRegister(AdvancedRegisters(), *this, a.offset, v));
}

bool Timer::Write(const Access& a) {
  const bool adv = kind_ == Kind::kAdvanced;
  if (a.offset == 0x14) {
    if (a.value & a.mask & 1u) {  // UG
      cnt_ = (Cms() == 0 && CountingDown()) ? arr_ : 0;
      psc_count_ = 0;
      down_ = false;
      LoadShadows();
      rep_ = rcr_;
      if (!(cr1_ & kUrs) && !(cr1_ & kUdis)) sr_ |= 1u;
    }
    return true;
  }
  if (a.offset == 0x20 && adv) {
    a.Apply(&ccer_, 0x0033FFFFu);
    return true;
  }
  if (std::uint32_t* ccr = Ccr(a.offset)) {
    const std::size_t i = static_cast<std::size_t>(ccr - ccr_.data());
    if (i >= 4) {
      a.Apply(ccr);
      return true;
    }
    a.Apply(ccr, 0xFFFFu);
    const int ch = static_cast<int>(i) + 1;
    const std::uint32_t m = CcmrOf(ch, ccmr1_, ccmr2_);
    if (!((m >> (3 + 8 * Slot(ch))) & 1u)) ccr_active_[i] = ccr_[i];  // no OCxPE
    return true;
  }
  const std::uint32_t cr1_before = cr1_;
  if (!WriteTableRegister(Registers(), *this, a)) {
    return adv && WriteTableRegister(AdvancedRegisters(), *this, a);
  }
  switch (a.offset) {
    case 0x00:
      // DIR is read-only in centre-aligned mode (RM0440 TIMx_CR1.DIR).
      if (Cms() != 0) cr1_ = (cr1_ & ~(1u << 4)) | (cr1_before & (1u << 4));
      if ((cr1_ & (1u << 3)) && !reported_mode_) {
        reported_mode_ = true;
        log_->Report(now_, name_, "one-pulse mode (CR1.OPM) is not modelled");
      }
      break;
    case 0x08:
      if (Sms() != 0 && !EncoderMode()) {
        log_->Report(now_, name_,
                     "SMCR.SMS = " + std::to_string(Sms()) +
                         ": only the quadrature encoder modes are modelled");
      }
      break;
    case 0x18:
    case 0x1C:
      for (int s = 0; s < 2; ++s) {
        const int ch = (a.offset == 0x18 ? 1 : 3) + s;
        const std::uint32_t reg = a.offset == 0x18 ? ccmr1_ : ccmr2_;
        const unsigned cc_s = (reg >> (8 * s)) & 3u;
        const unsigned m = OcMode(ch);
        if (cc_s == 0 && m > 7) {
          log_->Report(now_, name_,
                       "channel " + std::to_string(ch) + " OCxM = " + std::to_string(m) +
                           " (retriggerable/combined/asymmetric PWM) is not modelled");
        }
      }
      break;
    case 0x2C:
      if (!(cr1_ & kArpe)) arr_active_ = arr_;
      break;
    default:
      break;
  }
  return true;
}

}  // namespace mjc::g474model
