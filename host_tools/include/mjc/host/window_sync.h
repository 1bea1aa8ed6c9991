// mjc trial --sync-line: a GPIO output that marks the board's windows for other
// instruments (EMG, motion capture) recording it beside their own signals. The line is
// high during flexion windows and low during extension windows, so every window start
// is an edge — rising at each flexion (the windows the paper analyses), falling at each
// extension — and the level says which motion a sample of the instrument falls in. It
// is low at rest, before the first window and after the trial.
//
// The edge follows the board's WindowStart frame, which the board sends from its main
// loop right after the tick that starts the window; README (GPIO lines) says how far
// behind the window's start tick that puts the edge.
#pragma once

#include <cstdint>
#include <string>

#include "mjc/gpio/gpio_line.h"
#include "mjc/protocol/messages.h"

namespace mjc::host {

class WindowSync {
 public:
  // `line` must outlive this; it is set low (rest) at once by Rest().
  explicit WindowSync(gpio::OutputLine* line) : line_(line) {}

  // A window began: the line follows its motion. false with *why when the line could
  // not be set.
  bool OnWindowStart(const protocol::WindowStart& window, std::string* why);
  // The rest level (low): before the first window and after the last.
  bool Rest(std::string* why);

  // Window starts seen, and the edges they made (fewer when two windows of one motion
  // followed each other: a WindowStart lost on the bus).
  std::uint64_t windows() const { return windows_; }
  std::uint64_t edges() const { return edges_; }

 private:
  bool Level(bool high, std::string* why);

  gpio::OutputLine* line_;
  int level_ = -1;  // unknown until first set
  std::uint64_t windows_ = 0;
  std::uint64_t edges_ = 0;
};

}  // namespace mjc::host
