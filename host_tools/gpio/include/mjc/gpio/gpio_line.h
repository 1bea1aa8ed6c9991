// GPIO lines of the host: an edge input (the emergency-stop button) and outputs (the
// trigger to other instruments, a board's NRST), behind small interfaces so that the
// tools' logic is tested with fakes; GpiodInput and GpiodOutput are the Linux GPIO
// character device through libgpiod (Debian 12: libgpiod 1.6, its C++ bindings, the
// kernel's v1 uAPI).
//
// Levels are logical: `active` is the line's active level, high unless the line was
// opened active-low (the kernel then inverts values and edges for us).
//
// Errors never throw: Open returns nullptr with one line in *why naming the line and
// what is wrong — no such chip, no such line, the line held by another program (named
// by the consumer it registered), no permission.
#pragma once

#include <chrono>
#include <memory>
#include <string>

#include "mjc/gpio/line_spec.h"

namespace mjc::gpio {

enum class WaitResult : std::uint8_t {
  kEdge = 0,     // the line became active
  kTimeout = 1,  // no edge within the timeout
  kError = 2,    // the line could not be read (the reason is in `why`)
};

// An input watched for the edge into its active level.
class EdgeInput {
 public:
  virtual ~EdgeInput() = default;

  // Waits up to `timeout` for the line to become active. kEdge consumes one edge event
  // (those queued meanwhile follow, one a call); *timestamp is the kernel's time of it
  // (CLOCK_MONOTONIC), when given.
  WaitResult WaitActive(std::chrono::milliseconds timeout, std::string* why,
                        std::chrono::nanoseconds* timestamp = nullptr) {
    return DoWaitActive(timeout, why, timestamp);
  }
  // The level now: 1 active, 0 inactive, -1 on an error (*why says which).
  int Active(std::string* why) { return DoActive(why); }
  // "CHIP:LINE" as given, for messages.
  const std::string& name() const { return name_; }

 protected:
  explicit EdgeInput(std::string name) : name_(std::move(name)) {}

 private:
  virtual WaitResult DoWaitActive(std::chrono::milliseconds timeout, std::string* why,
                                  std::chrono::nanoseconds* timestamp) = 0;
  virtual int DoActive(std::string* why) = 0;
  std::string name_;
};

// An output driven to its active or inactive level.
class OutputLine {
 public:
  virtual ~OutputLine() = default;

  // false with the reason when the line could not be set.
  bool Set(bool active, std::string* why) { return DoSet(active, why); }
  const std::string& name() const { return name_; }

 protected:
  explicit OutputLine(std::string name) : name_(std::move(name)) {}

 private:
  virtual bool DoSet(bool active, std::string* why) = 0;
  std::string name_;
};

struct LineOptions {
  // Who holds the line, as gpioinfo shows it ("mjc estop"); at most 31 characters.
  std::string consumer = "mjc";
  bool active_low = false;
  // Outputs: drive only the low level and let the line float (a pull-up on the other
  // side makes it high) otherwise, as a reset line wants. The kernel emulates it on
  // chips that cannot (a released line becomes an input).
  bool open_drain = false;
  // Outputs: the level the line takes when it is requested.
  bool initially_active = false;
};

// The line `spec` names, as an input reporting its edges into the active level. The
// level at the request is Active()'s to read; only later edges are events.
std::unique_ptr<EdgeInput> OpenEdgeInput(const LineSpec& spec, const LineOptions& options,
                                         std::string* why);

// The line `spec` names, as an output at options.initially_active. The line stays
// requested (held against other programs) until the object is destroyed; the kernel
// then keeps the last level driven.
std::unique_ptr<OutputLine> OpenOutput(const LineSpec& spec, const LineOptions& options,
                                       std::string* why);

}  // namespace mjc::gpio
