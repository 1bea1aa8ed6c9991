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
  const std::uint64_t hz = !clock_on_                 ? 0
                           : kind_ == Kind::kAdvanced ? rcc_->tim_pclk2_whole_hz()
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
  if (!clock_on_ || !(cr1_ & kCen) || Sms() != 0 || (cr1_ & kUdis)) return kNever;
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
  if (channel > 2 || !(cr1_ & kCen) || !EncoderMode()) return;
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
  if (!(bdtr_ & kMoe)) {
    // Main output disabled: Hi-Z with OSSI = 0, else the idle level OISx/OISxN.
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

bool Timer::Read(const Access& a, std::uint32_t* v) {
  const bool adv = kind_ == Kind::kAdvanced;
  switch (a.offset) {
    case 0x00:
      *v = cr1_;
      return true;
    case 0x04:
      *v = cr2_;
      return true;
    case 0x08:
      *v = smcr_;
      return true;
    case 0x0C:
      *v = dier_;
      return true;
    case 0x10:
      *v = sr_;
      return true;
    case 0x14:
      *v = 0;
      return true;
    case 0x18:
      *v = ccmr1_;
      return true;
    case 0x1C:
      *v = ccmr2_;
      return true;
    case 0x20:
      *v = ccer_;
      return true;
    case 0x24:
      *v = cnt_;
      return true;
    case 0x28:
      *v = psc_;
      return true;
    case 0x2C:
      *v = arr_;
      return true;
    case 0x34:
    case 0x38:
    case 0x3C:
    case 0x40:
      *v = ccr_[(a.offset - 0x34) / 4];
      return true;
    case 0x58:
      *v = ecr_;
      return true;
    case 0x5C:
      *v = tisel_;
      return true;
    case 0x60:
      *v = af1_;
      return true;
    case 0x64:
      *v = af2_;
      return true;
    case 0x3DC:
      *v = dcr_;
      return true;
    case 0x3E0:
      *v = 0;
      return true;
    default:
      break;
  }
  if (!adv) return false;
  switch (a.offset) {
    case 0x30:
      *v = rcr_;
      return true;
    case 0x44:
      *v = bdtr_;
      return true;
    case 0x48:
      *v = ccr_[4];
      return true;
    case 0x4C:
      *v = ccr_[5];
      return true;
    case 0x50:
      *v = ccmr3_;
      return true;
    case 0x54:
      *v = dtr2_;
      return true;
    default:
      return false;
  }
}

bool Timer::Write(const Access& a) {
  const bool adv = kind_ == Kind::kAdvanced;
  const std::uint32_t v = a.value & a.mask;
  switch (a.offset) {
    case 0x00: {
      const std::uint32_t before = cr1_;
      a.Apply(&cr1_, 0x1BFFu);
      // DIR is read-only in centre-aligned mode (RM0440 TIMx_CR1.DIR).
      if (Cms() != 0) cr1_ = (cr1_ & ~(1u << 4)) | (before & (1u << 4));
      if ((cr1_ & (1u << 3)) && !reported_mode_) {
        reported_mode_ = true;
        log_->Report(now_, name_, "one-pulse mode (CR1.OPM) is not modelled");
      }
      return true;
    }
    case 0x04:
      a.Apply(&cr2_);
      return true;
    case 0x08:
      a.Apply(&smcr_);
      if (Sms() != 0 && !EncoderMode()) {
        log_->Report(now_, name_,
                     "SMCR.SMS = " + std::to_string(Sms()) +
                         ": only the quadrature encoder modes are modelled");
      }
      return true;
    case 0x0C:
      a.Apply(&dier_);
      return true;
    case 0x10:
      sr_ &= (v | ~a.mask);
      return true;  // rc_w0: writing 0 clears
    case 0x14:
      if (v & 1u) {  // UG
        cnt_ = (Cms() == 0 && CountingDown()) ? arr_ : 0;
        psc_count_ = 0;
        down_ = false;
        LoadShadows();
        rep_ = rcr_;
        if (!(cr1_ & kUrs) && !(cr1_ & kUdis)) sr_ |= 1u;
      }
      return true;
    case 0x18:
    case 0x1C: {
      std::uint32_t* reg = a.offset == 0x18 ? &ccmr1_ : &ccmr2_;
      a.Apply(reg);
      for (int s = 0; s < 2; ++s) {
        const int ch = (a.offset == 0x18 ? 1 : 3) + s;
        const unsigned cc_s = (*reg >> (8 * s)) & 3u;
        const unsigned m = OcMode(ch);
        if (cc_s == 0 && m > 7) {
          log_->Report(now_, name_,
                       "channel " + std::to_string(ch) + " OCxM = " + std::to_string(m) +
                           " (retriggerable/combined/asymmetric PWM) is not modelled");
        }
      }
      return true;
    }
    case 0x20:
      a.Apply(&ccer_, adv ? 0x0033FFFFu : 0x0000BBBBu);
      return true;
    case 0x24:
      a.Apply(&cnt_, 0xFFFFu);
      return true;
    case 0x28:
      a.Apply(&psc_, 0xFFFFu);
      return true;  // always preloaded
    case 0x2C:
      a.Apply(&arr_, 0xFFFFu);
      if (!(cr1_ & kArpe)) arr_active_ = arr_;
      return true;
    case 0x34:
    case 0x38:
    case 0x3C:
    case 0x40: {
      const std::size_t i = (a.offset - 0x34) / 4;
      a.Apply(&ccr_[i], 0xFFFFu);
      const int ch = static_cast<int>(i) + 1;
      const std::uint32_t m = CcmrOf(ch, ccmr1_, ccmr2_);
      if (!((m >> (3 + 8 * Slot(ch))) & 1u)) ccr_active_[i] = ccr_[i];  // no OCxPE
      return true;
    }
    case 0x58:
      a.Apply(&ecr_);
      return true;
    case 0x5C:
      a.Apply(&tisel_);
      return true;
    case 0x60:
      a.Apply(&af1_);
      return true;
    case 0x64:
      a.Apply(&af2_);
      return true;
    case 0x3DC:
      a.Apply(&dcr_);
      return true;
    case 0x3E0:
      return true;
    default:
      break;
  }
  if (!adv) return false;
  switch (a.offset) {
    case 0x30:
      a.Apply(&rcr_, 0xFFFFu);
      return true;
    case 0x44: {
      // LOCK levels are not modelled; MOE is what gates the outputs.
      a.Apply(&bdtr_);
      return true;
    }
    case 0x48:
      a.Apply(&ccr_[4]);
      return true;
    case 0x4C:
      a.Apply(&ccr_[5]);
      return true;
    case 0x50:
      a.Apply(&ccmr3_);
      return true;
    case 0x54:
      a.Apply(&dtr2_);
      return true;
    default:
      return false;
  }
}

}  // namespace mjc::g474model
