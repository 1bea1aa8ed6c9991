// The GPIO lines through libgpiod's C++ bindings (1.6, Debian 12), which wrap the
// kernel's GPIO character device: the chip looked up by label, name, path or number
// (gpiod_chip_open_lookup), the line by offset or name, requested with its flags. Every
// libgpiod error (a std::system_error carrying errno) becomes one line naming the line.
#include <cerrno>
#include <filesystem>
#include <gpiod.hpp>
#include <system_error>

#include "mjc/gpio/gpio_line.h"

namespace mjc::gpio {
namespace {

int ErrnoOf(const std::exception& e) {
  if (const auto* s = dynamic_cast<const std::system_error*>(&e))
    return s->code().value();
  return 0;
}

std::string Reason(const std::exception& e) {
  if (const auto* s = dynamic_cast<const std::system_error*>(&e))
    return s->code().message();
  return e.what();
}

// True when /dev holds no GPIO character device at all (a machine or container without
// GPIO), which deserves saying instead of blaming the chip's name.
bool NoChipsHere() {
  std::error_code error;
  for (const auto& entry : std::filesystem::directory_iterator("/dev", error)) {
    if (entry.path().filename().string().starts_with("gpiochip")) return false;
  }
  return true;
}

// "gpiochip0 [mjc-test-gpio]", as gpiodetect shows a chip.
std::string ChipTitle(const gpiod::chip& chip) {
  return chip.name() + " [" + chip.label() + "]";
}

std::optional<gpiod::chip> OpenChip(const LineSpec& spec, std::string* why) {
  try {
    return gpiod::chip(spec.chip, gpiod::chip::OPEN_LOOKUP);
  } catch (const std::exception& e) {
    const int error = ErrnoOf(e);
    if (error == ENOENT || error == ENODEV || error == ENOTTY) {
      *why = "no GPIO chip '" + spec.chip + "' for " + spec.text() +
             (NoChipsHere() ? " (this machine has no GPIO chip: /dev has no gpiochipN)"
                            : " (gpiodetect lists this machine's chips)");
    } else if (error == EACCES || error == EPERM) {
      *why = "cannot open the GPIO chip of " + spec.text() + ": " + Reason(e) +
             " (read and write access to /dev/gpiochipN is needed, e.g. the gpio group)";
    } else {
      *why = "cannot open the GPIO chip of " + spec.text() + ": " + Reason(e);
    }
    return std::nullopt;
  }
}

// The line `spec` names on its chip, or nullopt with *why.
std::optional<gpiod::line> FindLine(const LineSpec& spec, std::string* why) {
  const auto chip = OpenChip(spec, why);
  if (!chip) return std::nullopt;
  try {
    if (spec.offset) {
      if (*spec.offset >= chip->num_lines()) {
        *why = "GPIO chip " + ChipTitle(*chip) + " has lines 0.." +
               std::to_string(chip->num_lines() - 1) + ": no line " +
               std::to_string(*spec.offset) + " (" + spec.text() + ")";
        return std::nullopt;
      }
      return chip->get_line(*spec.offset);
    }
    gpiod::line line = chip->find_line(spec.name);
    if (!line) {
      *why = "GPIO chip " + ChipTitle(*chip) + " has no line named '" + spec.name +
             "' (" + spec.text() + "; gpioinfo " + chip->name() + " lists its lines)";
      return std::nullopt;
    }
    return line;
  } catch (const std::exception& e) {
    *why = "cannot read the lines of GPIO chip " + ChipTitle(*chip) + ": " + Reason(e);
    return std::nullopt;
  }
}

// Finds the line `spec` names and requests it as `type` with `flags` and the consumer
// in `options`, or says why not: "gpiochip0:5 is busy: held by 'mjc estop'" when
// another program (or a kernel driver) has it.
std::optional<gpiod::line> Request(const LineSpec& spec, const LineOptions& options,
                                   int type, std::bitset<32> flags, std::string* why) {
  auto line = FindLine(spec, why);
  if (!line) return std::nullopt;
  gpiod::line_request request;
  request.consumer = options.consumer;
  request.request_type = type;
  request.flags = flags;
  try {
    line->request(request, options.initially_active ? 1 : 0);
    return line;
  } catch (const std::exception& e) {
    if (ErrnoOf(e) == EBUSY) {
      std::string holder;
      try {
        line->update();
        holder = line->consumer();
      } catch (const std::exception&) {
      }
      *why = spec.text() + " is busy: held by " +
             (holder.empty() ? std::string("another program or driver")
                             : "'" + holder + "'") +
             " (gpioinfo " + line->get_chip().name() + " shows who holds its lines)";
    } else if (type == gpiod::line_request::EVENT_RISING_EDGE) {
      *why = "cannot watch " + spec.text() + " for edges: " + Reason(e) +
             " (does its GPIO chip give edge events?)";
    } else {
      *why = "cannot request " + spec.text() + ": " + Reason(e);
    }
    return std::nullopt;
  }
}

std::bitset<32> Flags(const LineOptions& options) {
  std::bitset<32> flags;
  if (options.active_low) flags |= gpiod::line_request::FLAG_ACTIVE_LOW;
  if (options.open_drain) flags |= gpiod::line_request::FLAG_OPEN_DRAIN;
  return flags;
}

class GpiodInput final : public EdgeInput {
 public:
  GpiodInput(const LineSpec& spec, gpiod::line line)
      : EdgeInput(spec.text()), line_(std::move(line)) {}
  ~GpiodInput() override { line_.release(); }

 private:
  WaitResult DoWaitActive(std::chrono::milliseconds timeout, std::string* why,
                          std::chrono::nanoseconds* timestamp) override {
    try {
      if (!line_.event_wait(timeout)) return WaitResult::kTimeout;
      const gpiod::line_event event = line_.event_read();
      if (timestamp != nullptr) *timestamp = event.timestamp;
      return WaitResult::kEdge;
    } catch (const std::exception& e) {
      // A signal (Ctrl-C: the tools' handlers do not restart calls) ends the wait early.
      if (ErrnoOf(e) == EINTR) return WaitResult::kTimeout;
      *why = "reading " + name() + ": " + Reason(e);
      return WaitResult::kError;
    }
  }
  int DoActive(std::string* why) override {
    try {
      return line_.get_value() != 0 ? 1 : 0;
    } catch (const std::exception& e) {
      *why = "reading " + name() + ": " + Reason(e);
      return -1;
    }
  }
  gpiod::line line_;
};

class GpiodOutput final : public OutputLine {
 public:
  GpiodOutput(const LineSpec& spec, gpiod::line line)
      : OutputLine(spec.text()), line_(std::move(line)) {}
  ~GpiodOutput() override { line_.release(); }

 private:
  bool DoSet(bool active, std::string* why) override {
    try {
      line_.set_value(active ? 1 : 0);
      return true;
    } catch (const std::exception& e) {
      *why = "setting " + name() + ": " + Reason(e);
      return false;
    }
  }
  gpiod::line line_;
};

}  // namespace

std::unique_ptr<EdgeInput> OpenEdgeInput(const LineSpec& spec, const LineOptions& options,
                                         std::string* why) {
  // With FLAG_ACTIVE_LOW the kernel reports the edge into the active level as rising.
  auto line = Request(spec, options, gpiod::line_request::EVENT_RISING_EDGE,
                      Flags(options) & ~gpiod::line_request::FLAG_OPEN_DRAIN, why);
  if (!line) return nullptr;
  return std::make_unique<GpiodInput>(spec, std::move(*line));
}

std::unique_ptr<OutputLine> OpenOutput(const LineSpec& spec, const LineOptions& options,
                                       std::string* why) {
  auto line =
      Request(spec, options, gpiod::line_request::DIRECTION_OUTPUT, Flags(options), why);
  if (!line) return nullptr;
  return std::make_unique<GpiodOutput>(spec, std::move(*line));
}

}  // namespace mjc::gpio
