#include "mjc/g474model/virtual_chip.h"

#include <string>
#include <utility>

namespace mjc::g474model {
namespace {
constexpr int kIrqs[] = {irq::kFlash,  irq::kFdcan1It0, irq::kFdcan1It1,
                         irq::kTim1Up, irq::kTim3,      irq::kSpi1};
}  // namespace

const char* ResetCauseName(ResetCause c) {
  switch (c) {
    case ResetCause::kSoftware:
      return "software (AIRCR.SYSRESETREQ)";
    case ResetCause::kIwdg:
      return "independent watchdog";
    case ResetCause::kPowerCut:
      return "power cut";
    case ResetCause::kOptionLoad:
      return "option-byte loading (FLASH_CR.OBL_LAUNCH)";
  }
  return "?";
}

VirtualChip::VirtualChip(ChipConfig config)
    : config_(std::move(config)),
      rcc_(&log_, config_.rcc),
      pwr_(&log_),
      rules_(&log_, &rcc_, &pwr_),
      flash_(&log_, config_.flash),
      gpio_{std::make_unique<GpioPort>(0, &log_), std::make_unique<GpioPort>(1, &log_),
            std::make_unique<GpioPort>(2, &log_), std::make_unique<GpioPort>(3, &log_),
            std::make_unique<GpioPort>(4, &log_), std::make_unique<GpioPort>(5, &log_),
            std::make_unique<GpioPort>(6, &log_)},
      mux_({gpio_[0].get(), gpio_[1].get(), gpio_[2].get(), gpio_[3].get(),
            gpio_[4].get(), gpio_[5].get(), gpio_[6].get()}),
      tim1_(Timer::Kind::kAdvanced, "TIM1", &log_, &rcc_),
      tim3_(Timer::Kind::kGeneral16, "TIM3", &log_, &rcc_),
      spi1_(&log_, &rcc_),
      fdcan1_(&log_, &rcc_),
      iwdg_(&log_, &rcc_),
      cortex_(&log_, &cycles_) {
  rcc_.SetClockChangeHook([this] { CheckClocks(); });
  pwr_.SetChangeHook([this] { CheckClocks(); });
  rcc_.SetPeripheralResetHook([this](Gate g) {
    if (Peripheral* block = GatedBlock(g)) block->Reset();
  });
  iwdg_.SetExpiryHook([this] { reset_pending_ = ResetCause::kIwdg; });
  cortex_.SetResetRequestHook([this] { reset_pending_ = ResetCause::kSoftware; });
  flash_.SetPowerCutHook([this] { reset_pending_ = ResetCause::kPowerCut; });
  flash_.options().SetLaunchHook([this] { reset_pending_ = ResetCause::kOptionLoad; });
  boot0_rng_.seed(config_.boot0_seed);
  for (auto& g : gpio_) {
    g->SetAfDriveSource([this](PinId p) { return AfDrive(p); });
    g->SetLevelHook([this](PinId p, bool level) { OnPinLevel(p, level); });
  }
  spi1_.SetBus([this](const SpiFrame& f) -> std::uint16_t {
    if (!as5047p_ || !as5047p_->selected()) return 0;  // MISO floats: reads 0
    const bool sck = mux_.PinCarrying(Signal::kSpi1Sck) == spi_wiring_.sck;
    const bool mosi = mux_.PinCarrying(Signal::kSpi1Mosi) == spi_wiring_.mosi;
    const bool miso = mux_.PinCarrying(Signal::kSpi1Miso) == spi_wiring_.miso;
    if (!sck) return 0;  // the sensor sees no clock
    SpiFrame seen = f;
    if (!mosi) seen.mosi = 0;
    const std::uint16_t answer = as5047p_->Exchange(seen);
    return miso ? answer : 0;
  });
  spi1_.SetFrameStartHook([this](const SpiFrame& f) {
    if (as5047p_ && as5047p_->selected() &&
        mux_.PinCarrying(Signal::kSpi1Sck) == spi_wiring_.sck) {
      as5047p_->OnFrameStart(f);
    }
  });
  reset_handler_ = [](ResetCause c) { throw ChipReset{c}; };
  UpdateGates();
  SetBoot0Pin(config_.boot0);
  SampleBoot();
}

VirtualChip::~VirtualChip() = default;

// ── Time ──────────────────────────────────────────────────────────────────────────

void VirtualChip::SpendCycles(std::uint64_t n) {
  std::uint64_t hz64 = rcc_.sysclk_whole_hz();
  if (hz64 == 0) {
    log_.Report(now_, "RCC", "the system clock is stopped (SYSCLK = 0): the CPU halts");
    hz64 = 16'000'000;
  }
  cycles_ += n;
  if (n == step_cycles_ && hz64 == step_hz_ && cycle_remainder_ < hz64) {
    // The same step as the last one at the same clock (every register access): its
    // quotient and remainder of n × 10^12 / f kept, the carry added by hand — the same
    // arithmetic as below without its division.
    std::uint64_t rest = static_cast<std::uint64_t>(cycle_remainder_) + step_rest_;
    Picoseconds ps = step_ps_;
    if (rest >= hz64) rest -= hz64, ++ps;
    cycle_remainder_ = rest;
    Sync(now_ + ps);
    return;
  }
  if (n < 1'000'000 && cycle_remainder_ < hz64 && hz64 < (std::uint64_t{1} << 32)) {
    step_cycles_ = n;
    step_hz_ = hz64;
    step_ps_ =
        static_cast<Picoseconds>(n * static_cast<std::uint64_t>(kPsPerSecond) / hz64);
    step_rest_ = n * static_cast<std::uint64_t>(kPsPerSecond) % hz64;
    // A register access's few cycles: 64 bits hold n × 10^12 plus the remainder
    // (< f < 2^32), the same arithmetic without 128-bit division.
    const std::uint64_t total = static_cast<std::uint64_t>(cycle_remainder_) +
                                n * static_cast<std::uint64_t>(kPsPerSecond);
    cycle_remainder_ = total % hz64;
    Sync(now_ + static_cast<Picoseconds>(total / hz64));
    return;
  }
  const auto hz = static_cast<unsigned __int128>(hz64);
  cycle_remainder_ += static_cast<unsigned __int128>(n) * kPsPerSecond;
  const auto ps = cycle_remainder_ / hz;
  cycle_remainder_ %= hz;
  Sync(now_ + static_cast<Picoseconds>(ps));
}

void VirtualChip::AdvanceTo(Picoseconds t) {
  // Step through every model event on the way, so that interrupts and resets happen
  // at their own time rather than at `t`.
  while (now_ < t) {
    Picoseconds next = t;
    for (Peripheral* p : std::initializer_list<Peripheral*>{
             &rcc_, &pwr_, &flash_, &tim1_, &tim3_, &spi1_, &fdcan1_, &iwdg_}) {
      const Picoseconds e = p->NextEvent();
      if (e > now_ && e < next) next = e;
    }
    Sync(next);
    ServiceInterrupts();
  }
}

void VirtualChip::Schedule(Picoseconds at, std::function<void()> fn) {
  events_.emplace(at, std::move(fn));
}

void VirtualChip::AdvanceModels(Picoseconds t) {
  now_ = t;
  AdvanceAll();
}

// Every model to now_. A model's state between two of its events changes only by its
// counting, which it catches up exactly when advanced over a longer interval, so the
// chip advances all of them only when an event is due (the deadline) or a world event
// or a block with wide effects (RCC, PWR, FLASH registers) needs them all current; an
// access to one block brings just that block (and what its state depends on) to now.
// The result is the same as advancing every model at every access, at a fraction of
// the cost (each access used to advance nine models).
void VirtualChip::AdvanceAll() {
  const Picoseconds t = now_;
  UpdateGates();
  rcc_.Advance(t);
  pwr_.Advance(t);
  flash_.Advance(t);
  tim1_.Advance(t);
  tim3_.Advance(t);
  spi1_.Advance(t);
  if (can_tx_ || can_rx_) {
    fdcan1_.SetPinsRouted(!can_tx_ || mux_.PinCarrying(Signal::kFdcan1Tx) == can_tx_,
                          !can_rx_ || mux_.PinCarrying(Signal::kFdcan1Rx) == can_rx_);
  }
  fdcan1_.Advance(t);
  iwdg_.Advance(t);
  cortex_.Advance(t);
  for (std::size_t i = 0; i < kTimedModels; ++i) next_[i] = Timed(i)->NextEvent();
  UpdateDeadline();
  lines_dirty_ = kAllLines;
}

// The models whose next event has come, each brought to now_ (all of them when it is
// the RCC's or the PWR's: a clock that changes moves every model's time base).
void VirtualChip::AdvanceDue() {
  if (next_[0] <= now_ || next_[1] <= now_) {
    AdvanceAll();
    return;
  }
  for (std::size_t i = 2; i < kTimedModels; ++i) {
    if (next_[i] > now_) continue;
    Peripheral* m = Timed(i);
    if (m == &fdcan1_ && (can_tx_ || can_rx_)) {
      fdcan1_.SetPinsRouted(!can_tx_ || mux_.PinCarrying(Signal::kFdcan1Tx) == can_tx_,
                            !can_rx_ || mux_.PinCarrying(Signal::kFdcan1Rx) == can_rx_);
    }
    m->Advance(now_);
    next_[i] = m->NextEvent();
    lines_dirty_ |= LinesOf(m);
  }
  UpdateDeadline();
}

// The interrupt lines (bits in kIrqs' order) a model drives.
unsigned VirtualChip::LinesOf(const Peripheral* m) const {
  if (m == &flash_) return 1u << 0;
  if (m == &fdcan1_) return 3u << 1;
  if (m == &tim1_) return 1u << 3;
  if (m == &tim3_) return 1u << 4;
  if (m == &spi1_) return 1u << 5;
  return kAllLines;
}

Peripheral* VirtualChip::Timed(std::size_t i) {
  Peripheral* const models[kTimedModels] = {&rcc_,  &pwr_,  &flash_,  &tim1_,
                                            &tim3_, &spi1_, &fdcan1_, &iwdg_};
  return models[i];
}

void VirtualChip::UpdateDeadline() {
  deadline_ = kNever;
  for (const Picoseconds e : next_) deadline_ = e < deadline_ ? e : deadline_;
}

void VirtualChip::Note(Peripheral* model) {
  std::size_t i = 0;
  if (model == &tim1_) {
    i = 3;
  } else if (model == &tim3_) {
    i = 4;
  } else if (model == &spi1_) {
    i = 5;
  } else if (model == &fdcan1_) {
    i = 6;
  } else if (model == &iwdg_) {
    i = 7;
  } else if (model == &flash_) {
    i = 2;
  } else {
    AdvanceAll();
    return;
  }
  next_[i] = model->NextEvent();
  UpdateDeadline();
  lines_dirty_ |= LinesOf(model);
}

void VirtualChip::Bring(const Route& route) {
  Peripheral* m = route.model;
  if (m == &cortex_) {
    cortex_.Advance(now_);
  } else if (m == &dbgmcu_) {
    return;  // no time base: its bits act only while the core is halted
  } else if (m == &rcc_ || m == &pwr_ || (m == &flash_ && route.kind == 0)) {
    AdvanceAll();  // clocks and latency: every model's time base may change
  } else if (m == &fdcan1_) {
    if (can_tx_ || can_rx_) {
      fdcan1_.SetPinsRouted(!can_tx_ || mux_.PinCarrying(Signal::kFdcan1Tx) == can_tx_,
                            !can_rx_ || mux_.PinCarrying(Signal::kFdcan1Rx) == can_rx_);
    }
    fdcan1_.Advance(now_);
  } else if (m == &tim1_ || m == &tim3_ || m == &spi1_ || m == &iwdg_ || m == &flash_) {
    m->Advance(now_);
  } else if (!OutputOnly(route)) {
    // A GPIO port: its AF pins show the timers' outputs, its inputs feed them. (A write
    // of ODR, BSRR or BRR moves only pins in output mode, which no timer sees.)
    tim1_.Advance(now_);
    tim3_.Advance(now_);
  }
}

bool VirtualChip::OutputOnly(const Route& route) const {
  return route.offset == 0x14 || route.offset == 0x18 || route.offset == 0x28;
}

void VirtualChip::Settle(const Route& route) {
  Peripheral* m = route.model;
  if (m == &rcc_ || m == &pwr_ || (m == &flash_ && route.kind == 0)) {
    UpdateGates();
    AdvanceAll();
  } else if (m == &cortex_ || m == &dbgmcu_) {
    return;  // no timed events (DWT counts CPU cycles; the NVIC is sampled below)
  } else if (m == &iwdg_) {
    // Starting the watchdog forces the LSI on (RM0440 IWDG): the RCC's next event too.
    next_[0] = rcc_.NextEvent();
    Note(m);
  } else if (m == &tim1_ || m == &tim3_ || m == &spi1_ || m == &flash_ || m == &fdcan1_) {
    Note(m);
  } else if (!OutputOnly(route)) {
    // A GPIO port: the timers' inputs may have moved (an encoder count, a wrap's UIF),
    // their next update events did not.
    lines_dirty_ |= LinesOf(&tim1_) | LinesOf(&tim3_);
  }
}

void VirtualChip::Sync(Picoseconds t) {
  if (t <= limit_ && t < deadline_ && (events_.empty() || events_.begin()->first > t) &&
      !reset_pending_) {
    if (t > now_) now_ = t;  // nothing due: the models catch up when next needed
    return;
  }
  if (t > limit_) {
    AdvanceModels(limit_);
    throw TimeLimitReached{limit_};
  }
  // World events in time order, the models brought to each event's time first.
  while (!events_.empty() && events_.begin()->first <= t) {
    auto it = events_.begin();
    const Picoseconds at = it->first < now_ ? now_ : it->first;
    auto fn = std::move(it->second);
    events_.erase(it);
    AdvanceModels(at);
    if (reset_pending_) DoReset(*reset_pending_);
    fn();
    lines_dirty_ = kAllLines;  // the world may have moved a line (a frame, a bus-off)
  }
  if (t > now_) now_ = t;
  if (now_ >= deadline_) AdvanceDue();
  if (reset_pending_) DoReset(*reset_pending_);
}

Peripheral* VirtualChip::GatedBlock(Gate g) {
  switch (g) {
    case Gate::kTim1:
      return &tim1_;
    case Gate::kTim3:
      return &tim3_;
    case Gate::kSpi1:
      return &spi1_;
    case Gate::kFdcan:
      return &fdcan1_;
    case Gate::kPwr:
      return &pwr_;
    default:
      if (g >= Gate::kGpioA && g <= Gate::kGpioG) {
        return gpio_[static_cast<std::size_t>(g) - static_cast<std::size_t>(Gate::kGpioA)]
            .get();
      }
      return nullptr;
  }
}

void VirtualChip::UpdateGates() {
  // The blocks whose models stop counting without their clock.
  const std::pair<Peripheral*, Gate> counting[] = {{&tim1_, Gate::kTim1},
                                                   {&tim3_, Gate::kTim3},
                                                   {&spi1_, Gate::kSpi1},
                                                   {&fdcan1_, Gate::kFdcan}};
  for (const auto& [block, gate] : counting) block->SetClockOn(rcc_.ClockEnabled(gate));
}

// ── Bus ───────────────────────────────────────────────────────────────────────────

std::optional<VirtualChip::Route> VirtualChip::Decode(std::uint32_t a) {
  // Most frequent first: the core's registers (the DWT's counter in the drivers' hold
  // loops), then the peripherals by their 1 KB block.
  if (a >= Dbgmcu::kBase && a < Dbgmcu::kBase + 0x400) {
    return Route{&dbgmcu_, a - Dbgmcu::kBase, std::nullopt, 0};
  }
  if (a >= 0xE0000000u && a < 0xE0100000u) {
    return Route{&cortex_, a - Cortex::kBase, std::nullopt, 0};
  }
  if (a >= GpioPort::kBase && a < GpioPort::kBase + 7 * 0x400) {
    const std::uint32_t port = (a - GpioPort::kBase) / 0x400;
    return Route{gpio_[port].get(), (a - GpioPort::kBase) % 0x400,
                 static_cast<Gate>(static_cast<unsigned>(Gate::kGpioA) + port), 0};
  }
  if (Flash::InArray(a) || Flash::InInfo(a)) return Route{&flash_, a, std::nullopt, 1};
  if (a >= Fdcan::kRamBase && a < Fdcan::kRamBase + Fdcan::kRamSize) {
    return Route{&fdcan1_, a - Fdcan::kRamBase, Gate::kFdcan, 2};
  }
  if (a >= Fdcan::kFdcan1Base && a < Fdcan::kFdcan1Base + 0x100) {
    return Route{&fdcan1_, a - Fdcan::kFdcan1Base, Gate::kFdcan, 0};
  }
  if (a >= Fdcan::kConfigBase && a < Fdcan::kConfigBase + 0x300) {
    return Route{&fdcan1_, a - Fdcan::kConfigBase, Gate::kFdcan, 3};
  }
  const std::uint32_t offset = a & 0x3FFu;
  switch (a & ~0x3FFu) {
    case Timer::kTim3Base:
      return Route{&tim3_, offset, Gate::kTim3, 0};
    case Iwdg::kBase:
      return Route{&iwdg_, offset, std::nullopt, 0};
    case Pwr::kBase:
      return Route{&pwr_, offset, Gate::kPwr, 0};
    case Timer::kTim1Base:
      return Route{&tim1_, offset, Gate::kTim1, 0};
    case Spi::kSpi1Base:
      return Route{&spi1_, offset, Gate::kSpi1, 0};
    case Rcc::kBase:
      return Route{&rcc_, offset, std::nullopt, 0};
    case Flash::kBase:
      return Route{&flash_, offset, Gate::kFlash, 0};
    default:
      return std::nullopt;
  }
}

std::uint32_t VirtualChip::Read(stm32g4::Address address, unsigned bytes) {
  SpendCycles(config_.access_cycles);
  if (address == Cortex::kBase + Cortex::kDwtCyccnt && bytes == 4) {
    // The drivers' hold loops read DWT_CYCCNT dozens of times a tick: a core register
    // with no timed events and no interrupt line, read straight from the model.
    cortex_.Advance(now_);
    const std::uint32_t count = cortex_.cyccnt();
    ServiceInterrupts(false);
    return count;
  }
  if ((bytes != 2 && bytes != 4) || (address & (bytes - 1)) != 0) {
    log_.Report(now_, "bus", "unaligned or odd-sized read at " + Hex(address));
    return 0;
  }
  if (cortex_.mpu_enabled()) {
    if (const auto region = cortex_.MpuDenies(address, false)) {
      ReportMpuFault(address, false, *region);
      ServiceInterrupts();
      return 0;
    }
  }
  const auto route = Decode(address);
  if (!route) {
    log_.Report(now_, "bus",
                "read at " + Hex(address) + ": no modelled peripheral there");
    ServiceInterrupts();
    return 0;
  }
  if (route->gate && !rcc_.ClockEnabled(*route->gate)) {
    log_.Report(now_, "bus",
                "read at " + Hex(address) +
                    " with the block's clock off in "
                    "RCC: reads 0");
    ServiceInterrupts();
    return 0;
  }
  // A read of the FLASH registers changes no clock and no latency (a write may): it
  // brings only the FLASH block, as its own events do (AdvanceDue). The flash driver
  // polls FLASH_SR a million times through a page erase; advancing every model at
  // each of those reads made the virtual board 10x slower than real time meanwhile.
  const bool flash_register = route->model == &flash_ && route->kind == 0;
  if (flash_register) {
    flash_.Advance(now_);
  } else {
    Bring(*route);
  }
  std::uint32_t value = 0;
  bool ok = false;
  if (route->kind == 1) {
    for (int tries = 0; tries < 3; ++tries) {
      ok = flash_.ReadMemory(address, bytes, &value);
      if (ok) break;
      const Picoseconds stall = flash_.TakeStall();
      if (stall == 0) break;
      Sync(stall);  // the bus waits for the busy bank
      Bring(*route);
    }
    if (!ok) log_.Report(now_, "bus", "read at " + Hex(address) + " outside the flash");
    Settle(*route);
    TakeFlashNmi();
    ServiceInterrupts();
    return value;
  }
  Access acc;
  acc.offset = route->offset & ~3u;
  acc.bytes = bytes;
  const unsigned shift = 8 * (route->offset & 3u);
  acc.mask = bytes == 4 ? 0xFFFFFFFFu : (0xFFFFu << shift);
  std::uint32_t word = 0;
  if (route->kind == 2) {
    ok = fdcan1_.ReadRam(acc, &word);
  } else if (route->kind == 3) {
    ok = fdcan1_.ReadConfig(acc, &word);
  } else if (route->model == &cortex_) {
    ok = cortex_.Read(acc, &word);
  } else {
    ok = route->model->Read(acc, &word);
  }
  if (!ok) {
    log_.Report(now_, "bus", "read at " + Hex(address) + ": reserved register");
    word = 0;
  }
  value = bytes == 4 ? word : (word >> shift) & 0xFFFFu;
  if (flash_register) {
    Note(&flash_);
  } else {
    Settle(*route);
  }
  ServiceInterrupts(false);
  return value;
}

void VirtualChip::Write(stm32g4::Address address, std::uint32_t value, unsigned bytes) {
  SpendCycles(config_.access_cycles);
  if ((bytes != 2 && bytes != 4) || (address & (bytes - 1)) != 0) {
    log_.Report(now_, "bus", "unaligned or odd-sized write at " + Hex(address));
    return;
  }
  if (cortex_.mpu_enabled()) {
    if (const auto region = cortex_.MpuDenies(address, true)) {
      ReportMpuFault(address, true, *region);
      ServiceInterrupts();
      return;
    }
  }
  const auto route = Decode(address);
  if (!route) {
    log_.Report(now_, "bus",
                "write at " + Hex(address) + ": no modelled peripheral there");
    ServiceInterrupts();
    return;
  }
  if (route->gate && !rcc_.ClockEnabled(*route->gate)) {
    log_.Report(
        now_, "bus",
        "write at " + Hex(address) + " with the block's clock off in RCC: ignored");
    ServiceInterrupts();
    return;
  }
  Bring(*route);
  if (route->kind == 1) {
    bool ok = false;
    for (int tries = 0; tries < 3 && !ok; ++tries) {
      if (!Flash::InArray(address)) break;
      ok = flash_.WriteMemory(address, value, bytes);
      if (!ok) {
        const Picoseconds stall = flash_.TakeStall();
        if (stall == 0) break;
        Sync(stall);
        Bring(*route);
      }
    }
    if (!ok) log_.Report(now_, "bus", "write at " + Hex(address) + " not taken");
    Settle(*route);
    if (reset_pending_) DoReset(*reset_pending_);
    ServiceInterrupts();
    return;
  }
  Access acc;
  acc.offset = route->offset & ~3u;
  acc.bytes = bytes;
  const unsigned shift = 8 * (route->offset & 3u);
  acc.mask = bytes == 4 ? 0xFFFFFFFFu : (0xFFFFu << shift);
  acc.value = bytes == 4 ? value : (value & 0xFFFFu) << shift;
  bool ok = false;
  if (route->kind == 2) {
    ok = fdcan1_.WriteRam(acc);
  } else if (route->kind == 3) {
    ok = fdcan1_.WriteConfig(acc);
  } else {
    ok = route->model->Write(acc);
  }
  if (!ok) log_.Report(now_, "bus", "write at " + Hex(address) + ": reserved register");
  if (route->model == &flash_ && acc.offset == 0) CheckClocks();
  if (route->model == &dbgmcu_ && halted_) ApplyDebugFreeze();  // a debugger's write
  Settle(*route);  // the clock gates too, after an RCC write
  // An NVIC write (a pending bit cleared while its line is still high) has every line
  // sampled again; Settle marked the lines of the other blocks.
  if (route->model == &cortex_) lines_dirty_ = kAllLines;
  if (reset_pending_) DoReset(*reset_pending_);
  ServiceInterrupts(false);
}

void VirtualChip::ReportMpuFault(std::uint32_t address, bool write, int region) {
  log_.Report(now_, "MPU",
              std::string(write ? "write" : "read") + " at " + Hex(address) +
                  (region < 0 ? " outside every region without PRIVDEFENA"
                              : " denied by region " + std::to_string(region)) +
                  ": MemManage (MMFSR.DACCVIOL) on the chip; not performed");
}

// ── Interrupts ────────────────────────────────────────────────────────────────────

bool VirtualChip::LineHigh(int n) const {
  switch (n) {
    case irq::kFlash:
      return flash_.irq();
    case irq::kFdcan1It0:
      return fdcan1_.line0();
    case irq::kFdcan1It1:
      return fdcan1_.line1();
    case irq::kTim1Up:
      return tim1_.update_irq();
    case irq::kTim3:
      return tim3_.update_irq();
    case irq::kSpi1:
      return spi1_.irq();
    default:
      return false;
  }
}

int VirtualChip::CurrentPriority() const {
  if (active_stack_.empty()) return 256;  // thread mode
  return static_cast<int>(cortex_.GroupPriority(cortex_.priority(active_stack_.back())));
}

void VirtualChip::SetHandler(int n, std::function<void()> handler) {
  handlers_[n] = std::move(handler);
}

void VirtualChip::MaskInterrupts(bool masked) {
  primask_ = masked;
  if (!masked) ServiceInterrupts();
}

void VirtualChip::ServiceInterrupts(bool sample) {
  for (;;) {
    // The lines are sampled unless nothing since the last sampling could have moved
    // one (an access to the DWT or the SCB's registers: the spin loops the drivers time
    // their holds with).
    const unsigned lines = sample ? kAllLines : lines_dirty_;
    if (lines != 0) {
      lines_dirty_ &= ~lines;
      for (std::size_t i = 0; i < std::size(kIrqs); ++i) {
        const int n = kIrqs[i];
        if (((lines >> i) & 1u) && LineHigh(n) && !cortex_.active(n)) {
          cortex_.SetPending(n, true);
        }
      }
    }
    sample = true;  // after a handler: its exit may leave a line high
    // A halted core takes nothing (the NVIC still records what is pending).
    if (halted_ || primask_ || !cortex_.AnyCandidate()) return;
    int best = -1;
    std::uint32_t best_priority = 0;
    for (int n = 0; n < Cortex::kIrqCount; ++n) {
      if (!cortex_.pending(n) || !cortex_.enabled(n) || cortex_.active(n)) continue;
      const std::uint32_t p = cortex_.priority(n);
      if (best < 0 || p < best_priority) best = n, best_priority = p;
    }
    if (best < 0 || static_cast<int>(cortex_.GroupPriority(cortex_.priority(best))) >=
                        CurrentPriority()) {
      return;
    }
    cortex_.SetPending(best, false);
    cortex_.SetActive(best, true);
    active_stack_.push_back(best);
    struct Exit {
      VirtualChip* chip;
      int n;
      bool done = false;
      ~Exit() {
        if (!done && !chip->active_stack_.empty()) {
          chip->active_stack_.pop_back();
          chip->cortex_.SetActive(n, false);
        }
      }
    } exit{this, best};
    SpendCycles(config_.exception_cycles);
    auto it = handlers_.find(best);
    if (it == handlers_.end() || !it->second) {
      log_.Report(now_, "NVIC",
                  "IRQ " + std::to_string(best) +
                      " taken with no handler registered (the default handler loops)");
      // Keep the IRQ from being taken again forever: disable it.
      Access a;
      a.offset = 0xE180 + 4 * static_cast<std::uint32_t>(best / 32);
      a.value = 1u << (best % 32);
      cortex_.Write(a);
    } else {
      it->second();
    }
    active_stack_.pop_back();
    cortex_.SetActive(best, false);
    exit.done = true;
    SpendCycles(config_.exception_cycles);
  }
}

void VirtualChip::WaitForInterrupt() {
  // Sleep until an interrupt is pending and enabled (with PRIMASK set, WFI still wakes
  // on it, the handler runs after PRIMASK is cleared).
  for (int guard = 0; guard < 10'000'000; ++guard) {
    for (int n : kIrqs) {
      if (LineHigh(n) && !cortex_.active(n)) cortex_.SetPending(n, true);
    }
    for (int n = 0; cortex_.AnyCandidate() && n < Cortex::kIrqCount; ++n) {
      if (cortex_.pending(n) && cortex_.enabled(n) &&
          static_cast<int>(cortex_.GroupPriority(cortex_.priority(n))) <
              CurrentPriority()) {
        ServiceInterrupts();
        return;
      }
    }
    // Every model current, so each one's next event is known (next_).
    if (deadline_ <= now_) AdvanceAll();
    Picoseconds next = events_.empty() ? kNever : events_.begin()->first;
    for (const Picoseconds e : next_) {
      if (e > now_ && e < next) next = e;
    }
    if (next == kNever) {
      log_.Report(now_, "NVIC",
                  "WFI with nothing that could wake the core: it sleeps "
                  "forever");
      if (limit_ != kNever) Sync(limit_ + 1);
      return;
    }
    Sync(next);
  }
}

void VirtualChip::TakeFlashNmi() {
  if (!flash_.TakeNmi()) return;
  // An NMI within the NMI handler stays pending until it returns (no re-entry); the
  // handler that reads a corrupt double word itself is not modelled further.
  if (in_nmi_) return;
  ++nmis_;
  if (!nmi_handler_) {
    log_.Report(now_, "NVIC",
                "NMI (flash ECC double error, ECCR " + Hex(flash_.eccr()) +
                    ") with no NMI handler: the default handler resets the chip");
    DoReset(ResetCause::kSoftware);
    return;
  }
  in_nmi_ = true;
  struct Exit {
    bool* flag;
    ~Exit() { *flag = false; }
  } exit{&in_nmi_};
  SpendCycles(config_.exception_cycles);
  nmi_handler_();
  SpendCycles(config_.exception_cycles);
}

// ── Resets ────────────────────────────────────────────────────────────────────────

void VirtualChip::PowerCut() {
  flash_.PowerLost();
  DoReset(ResetCause::kPowerCut);
}

// ── A debugger ────────────────────────────────────────────────────────────────────

void VirtualChip::ApplyDebugFreeze() {
  AdvanceAll();  // every model counts up to the instant the freeze changes
  iwdg_.SetFrozen(halted_ && dbgmcu_.iwdg_stop());
  tim1_.SetDebugStopped(halted_ && dbgmcu_.tim1_stop());
  tim3_.SetDebugStopped(halted_ && dbgmcu_.tim3_stop());
  AdvanceAll();  // their next events as frozen (or running again)
}

void VirtualChip::Halt() {
  Sync(now_);
  halted_ = true;
  ApplyDebugFreeze();
}

void VirtualChip::Resume() {
  halted_ = false;
  ApplyDebugFreeze();
  ServiceInterrupts();
}

void VirtualChip::DoReset(ResetCause cause) {
  reset_pending_.reset();
  ++resets_;
  halted_ = false;
  if (cause == ResetCause::kPowerCut) {
    dbgmcu_.PowerOn();
    flash_.PowerLost();
    rcc_.Reset();
    rcc_.PowerOn();
  } else {
    rcc_.Reset();
    // Internal resets drive NRST low too, so PINRSTF is set with the cause's flag.
    rcc_.SetResetFlags(csr::kPinrstf |
                       (cause == ResetCause::kIwdg         ? csr::kIwdgrstf
                        : cause == ResetCause::kOptionLoad ? csr::kOblrstf
                                                           : csr::kSftrstf));
  }
  // The option-byte loader runs at a power-on and at OBL_LAUNCH, not at other resets.
  if (cause == ResetCause::kPowerCut || cause == ResetCause::kOptionLoad) {
    flash_.options().Load(now_);
  }
  pwr_.Reset();
  flash_.Reset();
  for (auto& g : gpio_) g->Reset();
  tim1_.Reset();
  tim3_.Reset();
  spi1_.Reset();
  fdcan1_.Reset();
  iwdg_.Reset();
  tim1_.SetDebugStopped(false);
  tim3_.SetDebugStopped(false);
  cortex_.Reset();
  dbgmcu_.Reset();
  rules_.Reset();
  active_stack_.clear();
  in_nmi_ = false;
  primask_ = false;
  cycle_remainder_ = 0;
  SampleBoot();
  AdvanceAll();
  if (reset_handler_) reset_handler_(cause);
}

void VirtualChip::SetBoot0Pin(Boot0Pin pin) {
  config_.boot0 = pin;
  gpio('B').DriveInput(8, pin == Boot0Pin::kFloating
                              ? std::nullopt
                              : std::optional<bool>(pin == Boot0Pin::kPulledUp));
}

void VirtualChip::SampleBoot() {
  const std::uint32_t optr = flash_.options().loaded();
  bool pin = config_.boot0 == Boot0Pin::kPulledUp;
  if (config_.boot0 == Boot0Pin::kFloating) {
    pin = (boot0_rng_() & 1u) != 0;
    if ((optr & OptionBytes::kNSwBoot0) != 0) {
      log_.Report(now_, "BOOT",
                  "BOOT0 sampled from a floating PB8 (nSWBOOT0 = 1): the boot source is "
                  "chance (RM0440 §2.6)");
    }
  }
  boot_ = BootFrom(optr, pin);
}

void VirtualChip::RunWithoutImage() {
  for (;;) {
    if (deadline_ <= now_) AdvanceAll();
    Picoseconds next = events_.empty() ? kNever : events_.begin()->first;
    for (const Picoseconds e : next_) {
      if (e > now_ && e < next) next = e;
    }
    if (next == kNever) {
      if (limit_ != kNever) Sync(limit_ + 1);
      return;
    }
    Sync(next);
  }
}

// ── World ─────────────────────────────────────────────────────────────────────────

void VirtualChip::OnPinLevel(PinId p, bool level) {
  switch (mux_.SignalOn(p)) {
    case Signal::kTim3Ch1:
      tim3_.OnInput(1, level);
      break;
    case Signal::kTim3Ch2:
      tim3_.OnInput(2, level);
      break;
    case Signal::kTim1Ch1:
      tim1_.OnInput(1, level);
      break;
    case Signal::kTim1Ch2:
      tim1_.OnInput(2, level);
      break;
    default:
      break;
  }
  if (as5047p_ && p == spi_wiring_.cs) as5047p_->OnChipSelect(level, now_);
}

Drive VirtualChip::AfDrive(PinId p) const {
  switch (mux_.SignalOn(p)) {
    case Signal::kTim1Ch1:
      return tim1_.Level(1, false);
    case Signal::kTim1Ch2:
      return tim1_.Level(2, false);
    case Signal::kTim1Ch3:
      return tim1_.Level(3, false);
    case Signal::kTim1Ch4:
      return tim1_.Level(4, false);
    case Signal::kTim1Ch1n:
      return tim1_.Level(1, true);
    case Signal::kTim1Ch2n:
      return tim1_.Level(2, true);
    case Signal::kTim1Ch3n:
      return tim1_.Level(3, true);
    case Signal::kSpi1Sck:
    case Signal::kSpi1Mosi:
      return Drive::kLow;
    case Signal::kFdcan1Tx:
      return Drive::kHigh;  // recessive
    default:
      return Drive::kHighZ;
  }
}

OutputWave VirtualChip::PinWave(PinId p) const {
  const GpioPort& port = *gpio_[p.port];
  switch (port.mode(p.pin)) {
    case PinMode::kOutput: {
      const auto level = port.Level(p.pin);
      return level ? OutputWave{true, *level ? 1.0 : 0.0} : OutputWave{};
    }
    case PinMode::kAlternate:
      switch (mux_.SignalOn(p)) {
        case Signal::kTim1Ch1:
          return tim1_.Wave(1, false);
        case Signal::kTim1Ch2:
          return tim1_.Wave(2, false);
        case Signal::kTim1Ch3:
          return tim1_.Wave(3, false);
        case Signal::kTim1Ch4:
          return tim1_.Wave(4, false);
        case Signal::kTim1Ch1n:
          return tim1_.Wave(1, true);
        case Signal::kTim1Ch2n:
          return tim1_.Wave(2, true);
        case Signal::kTim1Ch3n:
          return tim1_.Wave(3, true);
        case Signal::kTim3Ch1:
          return tim3_.Wave(1, false);
        case Signal::kTim3Ch2:
          return tim3_.Wave(2, false);
        case Signal::kTim3Ch3:
          return tim3_.Wave(3, false);
        case Signal::kTim3Ch4:
          return tim3_.Wave(4, false);
        default:
          return {};
      }
    default:
      return {};
  }
}

BridgeDrive VirtualChip::HBridge(PinId in1, PinId in2, PinId enable) const {
  const OutputWave a = PinWave(in1), b = PinWave(in2);
  const auto en = gpio_[enable.port]->Level(enable.pin);
  BridgeDrive d;
  d.floating = !a.driven || !b.driven || !en;
  d.enabled = en.value_or(false) && a.driven && b.driven;
  d.duty = (a.driven ? a.duty : 0) - (b.driven ? b.duty : 0);
  return d;
}

void VirtualChip::AttachEncoder(PinId a, PinId b) {
  enc_a_ = a;
  enc_b_ = b;
  const int phase = static_cast<int>(encoder_pos_ & 3);
  gpio_[a.port]->DriveInput(a.pin, phase == 1 || phase == 2);
  gpio_[b.port]->DriveInput(b.pin, phase >= 2);
}

void VirtualChip::MoveEncoder(std::int64_t position) {
  if (!enc_a_ || !enc_b_) return;
  tim3_.Advance(now_);
  while (encoder_pos_ != position) {
    encoder_pos_ += position > encoder_pos_ ? 1 : -1;
    // Quadrature states (A, B) for position mod 4: 00, 10, 11, 01 (forward = A leads).
    const int phase = static_cast<int>(encoder_pos_ & 3);
    gpio_[enc_a_->port]->DriveInput(enc_a_->pin, phase == 1 || phase == 2);
    gpio_[enc_b_->port]->DriveInput(enc_b_->pin, phase >= 2);
  }
}

As5047p& VirtualChip::AttachAs5047p(SpiWiring wiring) {
  spi_wiring_ = wiring;
  as5047p_ = std::make_unique<As5047p>(&log_);
  const auto cs = gpio_[wiring.cs.port]->Level(wiring.cs.pin);
  as5047p_->OnChipSelect(cs.value_or(true), now_);
  return *as5047p_;
}

void VirtualChip::AttachCanTransceiver(PinId tx, PinId rx) {
  can_tx_ = tx;
  can_rx_ = rx;
}

bool VirtualChip::DeliverCanFrame(const CanBusFrame& frame) {
  Sync(now_);
  AdvanceAll();
  const bool taken = fdcan1_.Receive(frame);
  Note(&fdcan1_);
  ServiceInterrupts();
  return taken;
}

}  // namespace mjc::g474model
