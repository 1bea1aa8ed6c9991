// GPIO ports A..G of the STM32G474 (RM0440 chapter "General-purpose I/Os (GPIO)";
// offsets and the per-port reset values of MODER/OSPEEDR/PUPDR from ST's SVD v2.9) and
// the alternate-function routing of the signals the joint board uses.
//
// Covered: MODER, OTYPER, OSPEEDR, PUPDR, IDR (read-only: the pin's level in input,
// output and AF modes, 0 in analog mode), ODR, BSRR (set wins over reset), BRR,
// AFRL/AFRH. A pin's level: driven by ODR in output mode (open-drain drives only low), by
// the routed peripheral in AF mode, else by the world (DriveInput) or the pull resistor;
// a floating input reads 0.
//
// Alternate functions: a peripheral signal reaches a pin — and an input signal reaches
// the peripheral — only through a pin whose MODER is AF (10) and whose AFRx holds the AF
// number that DS12288 Table 13 "Alternate function" gives that pin for the signal. The
// table below holds, for every signal the board uses (TIM1 CH1..4/CH1N..3N, TIM3
// CH1..4, SPI1 SCK/MISO/MOSI/NSS, FDCAN1 RX/TX), every pin of the LQFP64 package that
// carries it, as ST's Open Pin Data transcribes the datasheet table (checked in
// zephyrproject-rtos/hal_stm32 dts/st/g4/stm32g474r(b-c-e)tx-pinctrl.dtsi, generated
// from it). Pins of larger packages (PD/PE/PG alternates) are not listed.
//
// Not covered: LCKR's lock sequence (plain storage), speed and drive strength (stored
// only), EXTI, analog switches, the other AF signals.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <optional>

#include "mjc/g474model/common.h"
#include "mjc/g474model/register_table.h"

namespace mjc::g474model {

enum class Signal : std::uint8_t {
  kNone,
  kTim1Ch1,
  kTim1Ch1n,
  kTim1Ch2,
  kTim1Ch2n,
  kTim1Ch3,
  kTim1Ch3n,
  kTim1Ch4,
  kTim3Ch1,
  kTim3Ch2,
  kTim3Ch3,
  kTim3Ch4,
  kSpi1Sck,
  kSpi1Miso,
  kSpi1Mosi,
  kSpi1Nss,
  kFdcan1Rx,
  kFdcan1Tx,
};
const char* SignalName(Signal s);

// A pin: port 0 = A … 6 = G, pin 0..15.
struct PinId {
  std::uint8_t port = 0;
  std::uint8_t pin = 0;
  bool operator==(const PinId&) const = default;
};
constexpr PinId Pin(char port, int pin) {
  return PinId{static_cast<std::uint8_t>(port - 'A'), static_cast<std::uint8_t>(pin)};
}
std::string PinName(PinId p);

struct AfEntry {
  PinId pin;
  std::uint8_t af;
  Signal signal;
};
// The DS12288 table rows for the board's signals (see above).
const std::array<AfEntry, 40>& AlternateFunctionTable();

enum class PinMode : std::uint8_t {
  kInput = 0,
  kOutput = 1,
  kAlternate = 2,
  kAnalog = 3
};

// The level a peripheral drives on an AF output: high, low, or not driven (Hi-Z, e.g. a
// timer output whose enable bits are off).
enum class Drive : std::uint8_t { kLow, kHigh, kHighZ };

class GpioPort final : public Peripheral {
 public:
  static constexpr std::uint32_t kBase = 0x48000000;  // port A; +0x400 per port

  GpioPort(int port, ViolationLog* log);
  bool Read(const Access& a, std::uint32_t* value) override;
  bool Write(const Access& a) override;
  void Reset() override;

  PinMode mode(int pin) const { return static_cast<PinMode>((moder_ >> (2 * pin)) & 3u); }
  unsigned af(int pin) const {
    return pin < 8 ? (afrl_ >> (4 * pin)) & 0xFu : (afrh_ >> (4 * (pin - 8))) & 0xFu;
  }
  bool open_drain(int pin) const { return (otyper_ >> pin) & 1u; }
  unsigned pull(int pin) const { return (pupdr_ >> (2 * pin)) & 3u; }  // 1 up, 2 down
  bool odr(int pin) const { return (odr_ >> pin) & 1u; }

  // World side: an external driver on the pin (true/false), or none.
  void DriveInput(int pin, std::optional<bool> level);
  std::optional<bool> external(int pin) const {
    return external_[static_cast<std::size_t>(pin)];
  }

  // The chip supplies what its peripherals drive on AF outputs, and is told about level
  // changes of every pin (inputs and outputs alike).
  void SetAfDriveSource(std::function<Drive(PinId)> source) {
    af_drive_ = std::move(source);
  }
  void SetLevelHook(std::function<void(PinId, bool)> hook) {
    level_hook_ = std::move(hook);
  }

  // Counts changes of MODER, AFRL and AFRH (and resets) in *counter: what the AF
  // routing depends on, so PinMux recomputes it only when one of these changed.
  void SetRoutingCounter(std::uint64_t* counter) { routing_counter_ = counter; }

  // The level on the pin now; nullopt when nothing drives it (floating).
  std::optional<bool> Level(int pin) const;
  // Re-evaluates the pins in `pins` (a bit per pin) and reports changes (after a
  // register or world change that may move them).
  void Refresh(std::uint32_t pins = 0xFFFFu);

 private:
  // The registers without code of their own (register_table.h).
  static RegisterTable<GpioPort> Registers();
  int port_;
  ViolationLog* log_;
  std::uint32_t moder_ = 0, otyper_ = 0, ospeedr_ = 0, pupdr_ = 0, odr_ = 0, lckr_ = 0,
                afrl_ = 0, afrh_ = 0;
  void NoteRouting() {
    if (routing_counter_ != nullptr) ++*routing_counter_;
  }
  std::uint64_t* routing_counter_ = nullptr;
  std::array<std::optional<bool>, 16> external_{};
  std::array<bool, 16> last_level_{};
  std::function<Drive(PinId)> af_drive_;
  std::function<void(PinId, bool)> level_hook_;
};

// Routing questions over all ports.
class PinMux {
 public:
  explicit PinMux(std::array<GpioPort*, 7> ports);
  // The signal a pin carries now (AF mode and a table AF number), or kNone.
  Signal SignalOn(PinId p) const;
  // The pins that carry `s` now (normally one).
  std::optional<PinId> PinCarrying(Signal s) const;
  GpioPort& port(int i) const { return *ports_[static_cast<std::size_t>(i)]; }

 private:
  static constexpr std::size_t kPins = 7 * 16;
  static constexpr std::size_t kSignals = static_cast<std::size_t>(Signal::kFdcan1Tx) + 1;
  // Every register access asks the routing (the chip checks the CAN pins on each):
  // it is recomputed only when a port's MODER/AFR changed since.
  void Update() const;

  std::array<GpioPort*, 7> ports_;
  std::uint64_t routing_changes_ = 0;
  mutable std::uint64_t generation_ = ~std::uint64_t{0};
  mutable std::array<Signal, kPins> signal_on_{};
  mutable std::array<std::optional<PinId>, kSignals> carrying_{};
};

}  // namespace mjc::g474model
