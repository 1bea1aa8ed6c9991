#include "mjc/host/emergency_stop.h"

#include "mjc/protocol/codec.h"

namespace mjc::host {

EmergencyStopWatch::EmergencyStopWatch(gpio::EdgeInput* line, CanLink* link,
                                       const EmergencyStopConfig& config, Clock now)
    : line_(line), link_(link), config_(config), now_(std::move(now)) {}

EmergencyStopWatch::Step EmergencyStopWatch::Send(std::string* why) {
  protocol::StopAll stop;
  stop.session = config_.session;
  if (before_send_) before_send_();
  if (!link_->Send(protocol::Encode(stop, protocol::kEveryNode), why))
    return Step::kError;
  ++sent_;
  next_repeat_ = now_() + config_.repeat;
  return Step::kSent;
}

EmergencyStopWatch::Step EmergencyStopWatch::Start(std::string* why) {
  const int level = line_->Active(why);
  if (level < 0) return Step::kError;
  if (level == 0) return Step::kQuiet;
  active_ = true;
  ++activations_;
  return Send(why);
}

EmergencyStopWatch::Step EmergencyStopWatch::Poll(std::chrono::milliseconds wait,
                                                  std::string* why) {
  if (active_) {
    const auto now = now_();
    if (now >= next_repeat_) {
      // Still pressed? Only then again.
      const int level = line_->Active(why);
      if (level < 0) return Step::kError;
      if (level == 1) return Send(why);
      active_ = false;
    } else {
      wait = std::min(wait,
                      std::chrono::ceil<std::chrono::milliseconds>(next_repeat_ - now));
    }
  }
  std::chrono::nanoseconds at{0};
  switch (line_->WaitActive(wait, why, &at)) {
    case gpio::WaitResult::kEdge:
      active_ = true;
      ++activations_;
      last_edge_ = at;
      return Send(why);
    case gpio::WaitResult::kTimeout:
      return Step::kQuiet;
    case gpio::WaitResult::kError:
      break;
  }
  return Step::kError;
}

EmergencyStopThread::EmergencyStopThread(std::unique_ptr<gpio::EdgeInput> line,
                                         std::unique_ptr<CanLink> link,
                                         const EmergencyStopConfig& config,
                                         std::atomic<bool>* raise)
    : line_(std::move(line)),
      link_(std::move(link)),
      watch_(line_.get(), link_.get(), config),
      raise_(raise),
      session_(config.session),
      line_name_(line_->name()) {
  // The flags before the frame: the board's stop can reach the tool's own link before
  // this thread would run again after sending.
  watch_.BeforeEachSend([this] {
    if (raise_ != nullptr) *raise_ = true;
    triggered_ = true;
  });
  thread_ = std::thread([this] { Run(); });
}

EmergencyStopThread::~EmergencyStopThread() {
  quit_ = true;
  thread_.join();
}

std::string EmergencyStopThread::error() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return error_;
}

void EmergencyStopThread::Run() {
  std::string why;
  // The waits are short so that the destructor is not kept waiting; an edge ends a
  // wait at once.
  constexpr std::chrono::milliseconds kWait{50};
  EmergencyStopWatch::Step step = watch_.Start(&why);
  while (step != EmergencyStopWatch::Step::kError) {
    activations_ = watch_.activations();
    if (quit_) return;
    step = watch_.Poll(kWait, &why);
  }
  // The button can no longer be heard: stop everything once more if the bus takes it.
  protocol::StopAll stop;
  stop.session = session_;
  std::string ignored;
  (void)link_->Send(protocol::Encode(stop, protocol::kEveryNode), &ignored);
  {
    std::lock_guard<std::mutex> lock(mutex_);
    error_ = why;
  }
  // After the reason: whoever sees triggered() can tell a failure from a press.
  if (raise_ != nullptr) *raise_ = true;
  triggered_ = true;
}

}  // namespace mjc::host
