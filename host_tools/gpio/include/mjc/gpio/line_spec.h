// A GPIO line as the tools name it: CHIP:LINE. CHIP is a GPIO chip of the kernel's
// character device, by its name ("gpiochip0"), its path ("/dev/gpiochip0"), its label
// ("pinctrl-bcm2711", as gpiodetect shows it in brackets) or its number ("0"); LINE is
// the line's offset on that chip ("17") or its name ("estop", as gpioinfo shows it in
// quotes). The text is split at its last colon, so a label may itself hold colons.
//
// Parsing checks the form only; whether the chip and line exist, and whether another
// program holds the line, is found when it is opened (gpio_line.h).
#pragma once

#include <optional>
#include <string>
#include <string_view>

namespace mjc::gpio {

struct LineSpec {
  std::string chip;
  std::optional<unsigned> offset;  // LINE given as a number
  std::string name;                // LINE given as a name (offset empty)

  // "CHIP:LINE", as the tools print it.
  std::string text() const {
    return chip + ":" + (offset ? std::to_string(*offset) : name);
  }
};

// Offsets above this are refused as typing errors: the largest GPIO chips have a few
// hundred lines, and the kernel's uAPI addresses at most 65,535.
inline constexpr unsigned kMaxLineOffset = 65535;

// nullopt with *why ("'gpiochip0' is not CHIP:LINE …") when `text` is not CHIP:LINE:
// no colon, an empty part, white space or control characters, an offset beyond
// kMaxLineOffset, or a name longer than the kernel's 31 characters.
std::optional<LineSpec> ParseLineSpec(std::string_view text, std::string* why);

}  // namespace mjc::gpio
