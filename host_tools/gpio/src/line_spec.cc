#include "mjc/gpio/line_spec.h"

#include <cstdint>

namespace mjc::gpio {
namespace {

// Printable ASCII other than the space: what a chip's name, path or label and a line's
// name may hold here (the kernel allows more, but no lab names a line "ß" or "a b").
bool Plain(std::string_view part) {
  for (const char c : part) {
    if (c <= ' ' || c > '~') return false;
  }
  return true;
}

bool Digits(std::string_view part) {
  if (part.empty()) return false;
  for (const char c : part) {
    if (c < '0' || c > '9') return false;
  }
  return true;
}

// The kernel keeps 32 bytes of a line's name, its terminating zero included.
constexpr std::size_t kMaxNameLength = 31;

}  // namespace

std::optional<LineSpec> ParseLineSpec(std::string_view text, std::string* why) {
  const auto refuse = [&](const std::string& what) {
    *why = "'" + std::string(text) + "' is not CHIP:LINE: " + what +
           " (e.g. gpiochip0:17, or gpiochip0:estop by the line's name)";
    return std::nullopt;
  };
  const std::size_t colon = text.rfind(':');
  if (colon == std::string_view::npos) return refuse("no ':' between chip and line");
  const std::string_view chip = text.substr(0, colon);
  const std::string_view line = text.substr(colon + 1);
  if (chip.empty()) return refuse("no chip before the ':'");
  if (line.empty()) return refuse("no line after the ':'");
  if (!Plain(chip)) return refuse("the chip has white space or control characters");
  if (!Plain(line)) return refuse("the line has white space or control characters");
  LineSpec spec;
  spec.chip = std::string(chip);
  if (Digits(line)) {
    std::uint64_t offset = 0;
    for (const char c : line) {
      offset = offset * 10 + static_cast<std::uint64_t>(c - '0');
      if (offset > kMaxLineOffset) {
        return refuse("line offset beyond " + std::to_string(kMaxLineOffset));
      }
    }
    spec.offset = static_cast<unsigned>(offset);
  } else {
    if (line.size() > kMaxNameLength) {
      return refuse("a line name has at most " + std::to_string(kMaxNameLength) +
                    " characters");
    }
    spec.name = std::string(line);
  }
  return spec;
}

}  // namespace mjc::gpio
