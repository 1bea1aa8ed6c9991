#include "mjc/g474model/gpio.h"

#include <string>

namespace mjc::g474model {

const char* SignalName(Signal s) {
  switch (s) {
    case Signal::kNone:
      return "none";
    case Signal::kTim1Ch1:
      return "TIM1_CH1";
    case Signal::kTim1Ch1n:
      return "TIM1_CH1N";
    case Signal::kTim1Ch2:
      return "TIM1_CH2";
    case Signal::kTim1Ch2n:
      return "TIM1_CH2N";
    case Signal::kTim1Ch3:
      return "TIM1_CH3";
    case Signal::kTim1Ch3n:
      return "TIM1_CH3N";
    case Signal::kTim1Ch4:
      return "TIM1_CH4";
    case Signal::kTim3Ch1:
      return "TIM3_CH1";
    case Signal::kTim3Ch2:
      return "TIM3_CH2";
    case Signal::kTim3Ch3:
      return "TIM3_CH3";
    case Signal::kTim3Ch4:
      return "TIM3_CH4";
    case Signal::kSpi1Sck:
      return "SPI1_SCK";
    case Signal::kSpi1Miso:
      return "SPI1_MISO";
    case Signal::kSpi1Mosi:
      return "SPI1_MOSI";
    case Signal::kSpi1Nss:
      return "SPI1_NSS";
    case Signal::kFdcan1Rx:
      return "FDCAN1_RX";
    case Signal::kFdcan1Tx:
      return "FDCAN1_TX";
  }
  return "?";
}

std::string PinName(PinId p) {
  return std::string("P") + static_cast<char>('A' + p.port) + std::to_string(p.pin);
}

const std::array<AfEntry, 40>& AlternateFunctionTable() {
  // DS12288 Table 13 (LQFP64 pins), via ST's Open Pin Data (see gpio.h).
  static const std::array<AfEntry, 40> kTable = {{
      {Pin('A', 8), 6, Signal::kTim1Ch1},   {Pin('C', 0), 2, Signal::kTim1Ch1},
      {Pin('A', 9), 6, Signal::kTim1Ch2},   {Pin('C', 1), 2, Signal::kTim1Ch2},
      {Pin('A', 10), 6, Signal::kTim1Ch3},  {Pin('C', 2), 2, Signal::kTim1Ch3},
      {Pin('A', 11), 11, Signal::kTim1Ch4}, {Pin('C', 3), 2, Signal::kTim1Ch4},
      {Pin('A', 7), 6, Signal::kTim1Ch1n},  {Pin('A', 11), 6, Signal::kTim1Ch1n},
      {Pin('B', 13), 6, Signal::kTim1Ch1n}, {Pin('C', 13), 4, Signal::kTim1Ch1n},
      {Pin('A', 12), 6, Signal::kTim1Ch2n}, {Pin('B', 0), 6, Signal::kTim1Ch2n},
      {Pin('B', 14), 6, Signal::kTim1Ch2n}, {Pin('B', 1), 6, Signal::kTim1Ch3n},
      {Pin('B', 9), 12, Signal::kTim1Ch3n}, {Pin('B', 15), 4, Signal::kTim1Ch3n},
      {Pin('F', 0), 6, Signal::kTim1Ch3n},  {Pin('A', 6), 2, Signal::kTim3Ch1},
      {Pin('B', 4), 2, Signal::kTim3Ch1},   {Pin('C', 6), 2, Signal::kTim3Ch1},
      {Pin('A', 4), 2, Signal::kTim3Ch2},   {Pin('A', 7), 2, Signal::kTim3Ch2},
      {Pin('B', 5), 2, Signal::kTim3Ch2},   {Pin('C', 7), 2, Signal::kTim3Ch2},
      {Pin('B', 0), 2, Signal::kTim3Ch3},   {Pin('B', 1), 2, Signal::kTim3Ch4},
      {Pin('A', 5), 5, Signal::kSpi1Sck},   {Pin('B', 3), 5, Signal::kSpi1Sck},
      {Pin('A', 6), 5, Signal::kSpi1Miso},  {Pin('B', 4), 5, Signal::kSpi1Miso},
      {Pin('A', 7), 5, Signal::kSpi1Mosi},  {Pin('B', 5), 5, Signal::kSpi1Mosi},
      {Pin('A', 4), 5, Signal::kSpi1Nss},   {Pin('A', 11), 9, Signal::kFdcan1Rx},
      {Pin('B', 8), 9, Signal::kFdcan1Rx},  {Pin('A', 12), 9, Signal::kFdcan1Tx},
      {Pin('B', 9), 9, Signal::kFdcan1Tx},  {Pin('A', 15), 5, Signal::kSpi1Nss},
  }};
  return kTable;
}

GpioPort::GpioPort(int port, ViolationLog* log) : port_(port), log_(log) { Reset(); }

void GpioPort::Reset() {
  // Reset values (SVD v2.9): port A keeps PA13/PA14/PA15 as SWD/JTAG (AF, pulls),
  // port B PB3/PB4 likewise; every other pin is analog (11).
  moder_ = port_ == 0 ? 0xABFFFFFFu : port_ == 1 ? 0xFFFFFEBFu : 0xFFFFFFFFu;
  ospeedr_ = port_ == 0 ? 0x0C000000u : port_ == 1 ? 0x000000C0u : 0;
  pupdr_ = port_ == 0 ? 0x64000000u : port_ == 1 ? 0x00000100u : 0;
  otyper_ = odr_ = lckr_ = afrl_ = afrh_ = 0;
  NoteRouting();
  Refresh();
}

std::optional<bool> GpioPort::Level(int pin) const {
  const PinId id{static_cast<std::uint8_t>(port_), static_cast<std::uint8_t>(pin)};
  const auto ext = external_[static_cast<std::size_t>(pin)];
  std::optional<bool> driven;
  switch (mode(pin)) {
    case PinMode::kOutput:
      if (!(odr(pin) && open_drain(pin))) driven = odr(pin);
      break;
    case PinMode::kAlternate:
      if (af_drive_) {
        const Drive d = af_drive_(id);
        if (d != Drive::kHighZ && !(d == Drive::kHigh && open_drain(pin))) {
          driven = d == Drive::kHigh;
        }
      }
      break;
    case PinMode::kAnalog:
      return ext;
    default:
      break;
  }
  if (driven) return driven;
  if (ext) return ext;
  if (pull(pin) == 1) return true;
  if (pull(pin) == 2) return false;
  return std::nullopt;
}

void GpioPort::Refresh(std::uint32_t pins) {
  for (int pin = 0; pin < 16; ++pin) {
    if (((pins >> pin) & 1u) == 0) continue;
    const bool level = Level(pin).value_or(false);
    if (level != last_level_[static_cast<std::size_t>(pin)]) {
      last_level_[static_cast<std::size_t>(pin)] = level;
      if (level_hook_) {
        level_hook_(
            PinId{static_cast<std::uint8_t>(port_), static_cast<std::uint8_t>(pin)},
            level);
      }
    }
  }
}

void GpioPort::DriveInput(int pin, std::optional<bool> level) {
  external_[static_cast<std::size_t>(pin)] = level;
  Refresh(1u << pin);  // an external driver moves its own pin only
}

RegisterTable<GpioPort> GpioPort::Registers() {
  using R = Register<GpioPort>;
  // IDR reads the pins and BSRR/BRR write through code of their own (see Read and Write).
  static constexpr R kTable[] = {
      R::ReadWrite(0x00, &GpioPort::moder_),
      R::ReadWrite(0x04, &GpioPort::otyper_, 0xFFFFu),
      R::ReadWrite(0x08, &GpioPort::ospeedr_),
      R::ReadWrite(0x0C, &GpioPort::pupdr_),
      R::ReadWrite(0x14, &GpioPort::odr_, 0xFFFFu),
      R::Fixed(0x18),  // BSRR is write-only
      R::ReadWrite(0x1C, &GpioPort::lckr_, 0x1FFFFu),
      R::ReadWrite(0x20, &GpioPort::afrl_),
      R::ReadWrite(0x24, &GpioPort::afrh_),
      R::Fixed(0x28),  // BRR is write-only
  };
  return kTable;
}

bool GpioPort::Read(const Access& a, std::uint32_t* v) {
  if (a.offset == 0x10) {
    std::uint32_t idr = 0;
    for (int pin = 0; pin < 16; ++pin) {
      if (mode(pin) != PinMode::kAnalog && Level(pin).value_or(false)) idr |= 1u << pin;
    }
    *v = idr;
    return true;
  }
  return ReadTableRegister(Registers(), *this, a.offset, v);
}

bool GpioPort::Write(const Access& a) {
  // ODR, BSRR and BRR move only the pins whose output bit changes; every other
  // register may change any pin's level.
  const std::uint32_t odr_before = odr_;
  const bool output_only = a.offset == 0x14 || a.offset == 0x18 || a.offset == 0x28;
  switch (a.offset) {
    case 0x10:
      return true;  // IDR is read-only
    case 0x18: {
      // "If both BSx and BRx are set, BSx has priority."
      const std::uint32_t v = a.value & a.mask;
      odr_ = (odr_ & ~(v >> 16)) | (v & 0xFFFFu);
      break;
    }
    case 0x28:
      odr_ &= ~(a.value & a.mask & 0xFFFFu);
      break;
    default:
      if (!WriteTableRegister(Registers(), *this, a)) return false;
      // MODER and AFRL/AFRH route the pins' signals.
      if (a.offset == 0x00 || a.offset == 0x20 || a.offset == 0x24) NoteRouting();
      break;
  }
  (void)log_;
  Refresh(output_only ? (odr_before ^ odr_) & 0xFFFFu : 0xFFFFu);
  return true;
}

PinMux::PinMux(std::array<GpioPort*, 7> ports) : ports_(ports) {
  for (GpioPort* p : ports_) p->SetRoutingCounter(&routing_changes_);
}

void PinMux::Update() const {
  const std::uint64_t generation = routing_changes_;
  if (generation == generation_) return;
  generation_ = generation;
  carrying_.fill(std::nullopt);
  for (std::uint8_t port = 0; port < 7; ++port) {
    const GpioPort& gp = *ports_[port];
    for (std::uint8_t pin = 0; pin < 16; ++pin) {
      Signal signal = Signal::kNone;
      if (gp.mode(pin) == PinMode::kAlternate) {
        const unsigned af = gp.af(pin);
        for (const auto& e : AlternateFunctionTable()) {
          if (e.pin == PinId{port, pin} && e.af == af) {
            signal = e.signal;
            break;
          }
        }
      }
      signal_on_[std::size_t{port} * 16 + pin] = signal;
      auto& first = carrying_[static_cast<std::size_t>(signal)];
      if (signal != Signal::kNone && !first) first = PinId{port, pin};
    }
  }
}

Signal PinMux::SignalOn(PinId p) const {
  Update();
  return signal_on_[std::size_t{p.port} * 16 + p.pin];
}

std::optional<PinId> PinMux::PinCarrying(Signal s) const {
  Update();
  return carrying_[static_cast<std::size_t>(s)];
}

}  // namespace mjc::g474model
