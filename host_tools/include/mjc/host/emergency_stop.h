// The emergency-stop button of a lab, on a GPIO line of the host: when the line becomes
// active, a StopAll goes on the bus at once (identifier 0x000, to every node: each
// board latches Fault::kEmergencyStop in its next tick and disables its bridge). Used by
// mjc estop (the watch alone) and by mjc trial, calibrate and monitor (--estop-line:
// the watch on a thread of its own, beside the tool's waits on its board).
//
// While the line stays active the stop is sent again every `repeat`, so that a board
// that is cleared (mjc clear), restarted or plugged in while the button is still
// pressed is stopped again. A watch that can no longer read its line or send on its
// link cannot stop anything: it sends a last StopAll if it can (a stop nobody asked
// for is safe, a button that no longer works is not) and ends with the reason.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "mjc/gpio/gpio_line.h"
#include "mjc/host/can_link.h"
#include "mjc/protocol/messages.h"

namespace mjc::host {

struct EmergencyStopConfig {
  // The StopAll again while the line stays active: as often as the host heartbeat.
  std::chrono::milliseconds repeat{100};
  protocol::SessionId session = 0;  // carried in the StopAll (names the sender)
};

// The watch, one step at a time (EmergencyStopThread runs it on a thread; mjc estop in
// its own loop).
class EmergencyStopWatch {
 public:
  using Clock = std::function<std::chrono::steady_clock::time_point()>;

  enum class Step : std::uint8_t {
    kQuiet = 0,  // nothing to do within the wait
    kSent = 1,   // a StopAll went out (an edge into active, or a repeat)
    kError = 2,  // the line or the link failed (*why); nothing more can be done
  };

  // `line` and `link` must outlive the watch. `now` is the clock of the repeats.
  EmergencyStopWatch(gpio::EdgeInput* line, CanLink* link,
                     const EmergencyStopConfig& config,
                     Clock now = &std::chrono::steady_clock::now);

  // Reads the line's level at the start: an active line (the button already pressed)
  // sends the StopAll at once. kQuiet, kSent or kError as Poll.
  Step Start(std::string* why);

  // Waits up to `wait` for the line to become active, and sends: at an edge into the
  // active level, at once; while it stays active, every `repeat`.
  Step Poll(std::chrono::milliseconds wait, std::string* why);

  // Edges into the active level seen (and the start, when the line was active then).
  std::uint64_t activations() const { return activations_; }
  std::uint64_t sent() const { return sent_; }
  bool active() const { return active_; }
  // The kernel's time (CLOCK_MONOTONIC) of the last edge, 0 before one.
  std::chrono::nanoseconds last_edge() const { return last_edge_; }

  // Called just before each StopAll goes on the bus. EmergencyStopThread raises its
  // flags there: a board answers a StopAll within a tick, and a tool that sees its
  // board stopped must already see why.
  void BeforeEachSend(std::function<void()> hook) { before_send_ = std::move(hook); }

 private:
  Step Send(std::string* why);

  gpio::EdgeInput* line_;
  CanLink* link_;
  EmergencyStopConfig config_;
  Clock now_;
  bool active_ = false;
  std::chrono::steady_clock::time_point next_repeat_{};
  std::uint64_t activations_ = 0;
  std::uint64_t sent_ = 0;
  std::chrono::nanoseconds last_edge_{0};
  std::function<void()> before_send_;
};

// The watch on a thread of its own. From just before its first StopAll goes out it stays
// triggered and raises the flag it was given (the tool's interrupt flag, which ends its
// waits on its boards); so does a failure of the line or the link (after a last
// StopAll).
class EmergencyStopThread {
 public:
  // Starts watching: `line` and `link` are its own. The start already sends the stop
  // when the line is active. `raise` (may be null) must outlive the thread.
  EmergencyStopThread(std::unique_ptr<gpio::EdgeInput> line,
                      std::unique_ptr<CanLink> link, const EmergencyStopConfig& config,
                      std::atomic<bool>* raise);
  ~EmergencyStopThread();
  EmergencyStopThread(const EmergencyStopThread&) = delete;
  EmergencyStopThread& operator=(const EmergencyStopThread&) = delete;

  // A StopAll went out, or is going out (or the watch failed).
  bool triggered() const { return triggered_; }
  // Edges into the active level so far (EmergencyStopWatch::activations).
  std::uint64_t activations() const { return activations_; }
  // Why the watch failed, empty while it works.
  std::string error() const;
  const std::string& line_name() const { return line_name_; }

 private:
  void Run();

  std::unique_ptr<gpio::EdgeInput> line_;
  std::unique_ptr<CanLink> link_;
  EmergencyStopWatch watch_;
  std::atomic<bool>* raise_;
  protocol::SessionId session_;
  std::string line_name_;
  std::atomic<bool> triggered_{false};
  std::atomic<std::uint64_t> activations_{0};
  std::atomic<bool> quit_{false};
  mutable std::mutex mutex_;
  std::string error_;
  std::thread thread_;
};

}  // namespace mjc::host
