#include "hal/stm32g4/gpio.h"

namespace mjc::stm32g4 {
namespace {

void Modify(Address address, const Field& field, std::uint32_t value) {
  Write32(address, field.With(Read32(address), value));
}

}  // namespace

void ConfigurePin(const PinConfig& config) {
  const Address port = PortAddress(config.pin.port);
  const unsigned n = config.pin.number & 15u;
  // Alternate function first, then type, speed and pull, then the mode: the pin
  // changes function only once everything it will need is in place (RM0440 §9.3.2,
  // "I/O pin alternate function multiplexer and mapping": select the AF before setting
  // MODER to alternate, to avoid a glitch on the other function).
  if (config.mode == PinMode::kAlternate) {
    if (n < 8) {
      Modify(port + gpio::kAfrl, gpio::kAfl[n], config.alternate);
    } else {
      Modify(port + gpio::kAfrh, gpio::kAfh[n - 8], config.alternate);
    }
  }
  Modify(port + gpio::kOtyper, gpio::kOt[n], static_cast<std::uint32_t>(config.type));
  Modify(port + gpio::kOspeedr, gpio::kOspeed[n],
         static_cast<std::uint32_t>(config.speed));
  Modify(port + gpio::kPupdr, gpio::kPupd[n], static_cast<std::uint32_t>(config.pull));
  if (config.mode == PinMode::kOutput) WritePin(config.pin, config.initial_high);
  Modify(port + gpio::kModer, gpio::kMode[n], static_cast<std::uint32_t>(config.mode));
}

}  // namespace mjc::stm32g4
