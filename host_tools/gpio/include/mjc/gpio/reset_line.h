// A board's reset line: the STM32G474's NRST, active low, wired to a host GPIO line
// configured open drain. Pulled low, the board resets; released, the line floats back
// up through the board's own pull-up and the board starts (its bootloader's 200 ms hold
// window begins ~3 ms later, firmware/bootloader/BOOTLOADER.md). The host never drives
// it high: a push-pull output would fight the board's reset button and its supervisor.
#pragma once

#include <chrono>
#include <functional>
#include <memory>
#include <string>

#include "mjc/gpio/gpio_line.h"

namespace mjc::gpio {

// How long the host holds NRST low. The G474 resets on any low pulse longer than its
// filter's (DS12288: an NRST pulse of 350 ns is never filtered out; from memory of the
// datasheet, not a source at hand). 10 ms is ~30,000 times that: it covers a slow GPIO
// controller (a USB or I2C expander takes a millisecond or more per write, and Linux may
// delay the release by as much), the discharge of the 100 nF capacitor a board puts on
// NRST (through the open-drain transistor: microseconds), and is short against the
// bootloader's 200 ms hold window that a flash must catch after the release.
inline constexpr std::chrono::milliseconds kResetPulse{10};

// The options a reset line is opened with: open drain, active low, released.
LineOptions ResetLineOptions(std::string consumer);

// Opens `spec` as a reset line (ResetLineOptions): released, held against other
// programs until destroyed. nullptr with *why as OpenOutput.
std::unique_ptr<OutputLine> OpenResetLine(const LineSpec& spec, std::string consumer,
                                          std::string* why);

// Pulses a board's reset: drives `line` active (NRST low), waits `low` (at least; a
// loaded machine waits longer, which resets all the same), releases it. `sleep` is
// how it waits (tests give their own). false with *why when the line could not be set;
// the line is then released if it can be.
bool PulseReset(OutputLine& line, std::string* why,
                std::chrono::nanoseconds low = kResetPulse,
                const std::function<void(std::chrono::nanoseconds)>& sleep = nullptr);

}  // namespace mjc::gpio
