#include "mjc/g474model/iwdg.h"

#include <string>

namespace mjc::g474model {
namespace {
constexpr Picoseconds LsiCycles(double n, double lsi_hz) {
  return static_cast<Picoseconds>(n / lsi_hz * 1e12);
}
}  // namespace

void Iwdg::Reset() {
  running_ = unlocked_ = frozen_ = false;
  pr_ = 0;
  rlr_ = winr_ = counter_ = 0xFFF;
  prescale_count_ = 0;
  lsi_ticks_.Reset();
  pvu_until_ = rvu_until_ = wvu_until_ = 0;
}

std::uint32_t Iwdg::Divider() const { return 4u << (pr_ > 6 ? 6 : pr_); }

void Iwdg::Expire(const char* why) {
  log_->Report(now_, "IWDG", std::string("watchdog reset: ") + why);
  running_ = false;
  if (expiry_hook_) expiry_hook_();
}

void Iwdg::Advance(Picoseconds now) {
  const Picoseconds dt = now - now_;
  now_ = now;
  if (!running_ || frozen_) return;
  std::uint64_t cycles = lsi_ticks_.Advance(dt, rcc_->lsi_hz());
  const std::uint32_t div = Divider();
  while (cycles > 0 && running_) {
    const std::uint64_t to_tick = div - prescale_count_;
    if (cycles < to_tick) {
      prescale_count_ += static_cast<std::uint32_t>(cycles);
      break;
    }
    cycles -= to_tick;
    prescale_count_ = 0;
    if (counter_ == 0) {
      Expire("the counter reached the end of its count (no reload in time)");
      return;
    }
    --counter_;
  }
}

Picoseconds Iwdg::NextEvent() const {
  Picoseconds next = kNever;
  for (Picoseconds t : {pvu_until_, rvu_until_, wvu_until_}) {
    if (t > now_ && t < next) next = t;
  }
  if (running_ && !frozen_ && rcc_->lsi_hz() > 0) {
    const std::uint64_t cycles =
        static_cast<std::uint64_t>(counter_ + 1) * Divider() - prescale_count_;
    const Picoseconds t = now_ + lsi_ticks_.UntilTicks(cycles, rcc_->lsi_hz());
    if (t < next) next = t;
  }
  return next;
}

RegisterTable<Iwdg> Iwdg::Registers() {
  using R = Register<Iwdg>;
  // KR takes the key sequence and PR, RLR, WINR are locked behind it (see Write); SR
  // reads the update flags through Read.
  static constexpr R kTable[] = {
      R::Fixed(0x00),  // KR: "write only, read 0x0000"
      R::ReadWrite(0x04, &Iwdg::pr_, 7u),
      R::ReadWrite(0x08, &Iwdg::rlr_, 0xFFFu),
      R::ReadWrite(0x10, &Iwdg::winr_, 0xFFFu),
  };
  return kTable;
}

bool Iwdg::Read(const Access& a, std::uint32_t* v) {
  if (a.offset == 0x0C) {
    *v = (now_ < pvu_until_ ? 1u : 0u) | (now_ < rvu_until_ ? 2u : 0u) |
         (now_ < wvu_until_ ? 4u : 0u);
    return true;
  }
  return ReadTableRegister(Registers(), *this, a.offset, v);
}

bool Iwdg::Write(const Access& a) {
  const double lsi = rcc_->lsi_hz() > 0 ? rcc_->lsi_hz() : 32000.0;
  const Picoseconds update = LsiCycles(5, lsi);
  switch (a.offset) {
    case 0x00: {
      const std::uint32_t key = a.value & a.mask & 0xFFFFu;
      if (key == 0xCCCC) {
        rcc_->ForceLsiOn();
        if (!running_) {
          running_ = true;
          counter_ = rlr_;
          prescale_count_ = 0;
          lsi_ticks_.Reset();
        }
      } else if (key == 0x5555) {
        unlocked_ = true;
      } else if (key == 0xAAAA) {
        if (running_ && winr_ < 0xFFF && counter_ > winr_) {
          Expire("reload outside the window (counter above WINR)");
          return true;
        }
        counter_ = rlr_;
        unlocked_ = false;
      } else {
        unlocked_ = false;
      }
      return true;
    }
    case 0x04:
    case 0x08:
    case 0x10: {
      if (!unlocked_) {
        log_->Report(now_, "IWDG", "PR/RLR/WINR written without the 0x5555 key: ignored");
        return true;
      }
      Picoseconds* busy = a.offset == 0x04   ? &pvu_until_
                          : a.offset == 0x08 ? &rvu_until_
                                             : &wvu_until_;
      if (now_ < *busy) {
        log_->Report(now_, "IWDG",
                     "register written while its previous update is still in progress "
                     "(SR.PVU/RVU/WVU set): RM0440 asks to wait for the flag");
      }
      WriteTableRegister(Registers(), *this, a);
      if (a.offset == 0x10 && running_) counter_ = rlr_;  // writing the window reloads
      *busy = now_ + update;
      return true;
    }
    case 0x0C:
      return true;
    default:
      return false;
  }
}

}  // namespace mjc::g474model
