// The host's GPIO side without a GPIO chip: CHIP:LINE names and the config file's
// lines, the reset pulse's order and length, the emergency-stop watch (its StopAll on an
// in-process bus, decoded), and the sync line's edges at window starts. The same code
// against the kernel's GPIO character device: tests/kernel/gpio.sh.
#include <gtest/gtest.h>

#include <chrono>
#include <deque>
#include <string>
#include <vector>

#include "mjc/gpio/line_spec.h"
#include "mjc/gpio/reset_line.h"
#include "mjc/host/board_client.h"
#include "mjc/host/config.h"
#include "mjc/host/emergency_stop.h"
#include "mjc/host/window_sync.h"
#include "mjc/protocol/codec.h"

namespace {

using namespace mjc;
using namespace std::chrono_literals;

// --- CHIP:LINE ---------------------------------------------------------------------

TEST(LineSpec, ChipByNamePathLabelOrNumberAndLineByOffsetOrName) {
  std::string why;
  auto s = gpio::ParseLineSpec("gpiochip0:17", &why);
  ASSERT_TRUE(s) << why;
  EXPECT_EQ(s->chip, "gpiochip0");
  EXPECT_EQ(s->offset, 17u);
  EXPECT_TRUE(s->name.empty());
  s = gpio::ParseLineSpec("/dev/gpiochip2:estop", &why);
  ASSERT_TRUE(s) << why;
  EXPECT_EQ(s->chip, "/dev/gpiochip2");
  EXPECT_FALSE(s->offset);
  EXPECT_EQ(s->name, "estop");
  s = gpio::ParseLineSpec("0:0", &why);
  ASSERT_TRUE(s) << why;
  EXPECT_EQ(s->chip, "0");
  EXPECT_EQ(s->offset, 0u);
  // A label with colons: the line follows the last one.
  s = gpio::ParseLineSpec("ftdi-cbus:1-1.2:3", &why);
  ASSERT_TRUE(s) << why;
  EXPECT_EQ(s->chip, "ftdi-cbus:1-1.2");
  EXPECT_EQ(s->offset, 3u);
  EXPECT_EQ(s->text(), "ftdi-cbus:1-1.2:3");
  // A line name that is not all digits stays a name.
  s = gpio::ParseLineSpec("gpiochip0:17a", &why);
  ASSERT_TRUE(s) << why;
  EXPECT_EQ(s->name, "17a");
  EXPECT_EQ(gpio::ParseLineSpec("gpiochip0:65535", &why)->offset, 65535u);
}

TEST(LineSpec, MalformedNamesAreRefusedSayingWhy) {
  const std::vector<std::pair<std::string, std::string>> bad = {
      {"gpiochip0", "no ':'"},
      {":3", "no chip"},
      {"gpiochip0:", "no line"},
      {"gpio chip0:3", "white space"},
      {"gpiochip0:es top", "white space"},
      {"gpiochip0:\t3", "white space"},
      {"gpiochip0:65536", "beyond 65535"},
      {"gpiochip0:99999999999999999999", "beyond 65535"},
      {"gpiochip0:" + std::string(32, 'a'), "at most 31"},
  };
  for (const auto& [text, reason] : bad) {
    std::string why;
    EXPECT_FALSE(gpio::ParseLineSpec(text, &why)) << text;
    EXPECT_NE(why.find("is not CHIP:LINE"), std::string::npos) << why;
    EXPECT_NE(why.find(reason), std::string::npos) << text << ": " << why;
  }
}

TEST(ToolConfig, GpioLinesFromTheConfigFile) {
  std::string why;
  const auto c = host::ParseToolConfig(
      R"({"iface": "can0", "estop_line": "gpiochip0:estop", "estop_active": "low",
          "sync_line": "pinctrl-bcm2711:17",
          "reset_lines": {"1": "gpiochip1:20", "8": "gpiochip1:nrst8"}})",
      "c.json", &why);
  ASSERT_TRUE(c) << why;
  ASSERT_TRUE(c->estop_line);
  EXPECT_EQ(c->estop_line->text(), "gpiochip0:estop");
  EXPECT_EQ(c->estop_active_low, true);
  ASSERT_TRUE(c->sync_line);
  EXPECT_EQ(c->sync_line->chip, "pinctrl-bcm2711");
  EXPECT_EQ(c->sync_line->offset, 17u);
  ASSERT_EQ(c->reset_lines.size(), 2u);
  EXPECT_EQ(c->reset_lines.at(1).text(), "gpiochip1:20");
  EXPECT_EQ(c->reset_lines.at(8).name, "nrst8");
  // None given: none in force.
  const auto empty = host::ParseToolConfig("{}", "c.json", &why);
  ASSERT_TRUE(empty);
  EXPECT_FALSE(empty->estop_line);
  EXPECT_FALSE(empty->estop_active_low);
  EXPECT_TRUE(empty->reset_lines.empty());
}

TEST(ToolConfig, BadGpioEntriesNameTheFileAndKey) {
  const std::vector<std::pair<std::string, std::string>> bad = {
      {R"({"estop_line": "gpiochip0"})", "'estop_line': 'gpiochip0' is not CHIP:LINE"},
      {R"({"sync_line": 17})", "'sync_line' must be a GPIO line as a string"},
      {R"({"estop_active": "pressed"})", "'estop_active' must be \"high\" or \"low\""},
      {R"({"reset_lines": ["gpiochip0:1"]})", "'reset_lines' must be an object"},
      {R"({"reset_lines": {"9": "gpiochip0:1"}})", "'9' is not a node id 1..8"},
      {R"({"reset_lines": {"2": "gpiochip0: 1"}})", "'reset_lines.2'"},
      {R"({"estop_lines": "gpiochip0:1"})", "did you mean 'estop_line'"},
  };
  for (const auto& [text, reason] : bad) {
    std::string why;
    EXPECT_FALSE(host::ParseToolConfig(text, "lab.json", &why)) << text;
    EXPECT_EQ(why.rfind("lab.json: ", 0), 0u) << why;
    EXPECT_NE(why.find(reason), std::string::npos) << text << ": " << why;
  }
}

// --- fakes -------------------------------------------------------------------------

// An output that records every level it is set to; `fail_after` sets fail.
class RecordingOutput final : public gpio::OutputLine {
 public:
  RecordingOutput() : OutputLine("fake:0") {}
  std::vector<bool> levels;
  int fail_at = -1;  // the Set call (0-based) that fails

 private:
  bool DoSet(bool active, std::string* why) override {
    if (static_cast<int>(levels.size()) == fail_at) {
      *why = "setting fake:0: Input/output error";
      fail_at = -1;
      return false;
    }
    levels.push_back(active);
    return true;
  }
};

// An input scripted by the test: queued edges, a level, a failure.
class ScriptedInput final : public gpio::EdgeInput {
 public:
  ScriptedInput() : EdgeInput("fake:estop") {}
  std::deque<std::chrono::nanoseconds> edges;  // timestamps of edges to report
  bool level = false;
  bool broken = false;
  std::vector<std::chrono::milliseconds> waits;  // every timeout asked for

 private:
  gpio::WaitResult DoWaitActive(std::chrono::milliseconds timeout, std::string* why,
                                std::chrono::nanoseconds* timestamp) override {
    waits.push_back(timeout);
    if (broken) {
      *why = "reading fake:estop: No such device";
      return gpio::WaitResult::kError;
    }
    if (edges.empty()) return gpio::WaitResult::kTimeout;
    if (timestamp != nullptr) *timestamp = edges.front();
    edges.pop_front();
    level = true;
    return gpio::WaitResult::kEdge;
  }
  int DoActive(std::string* why) override {
    if (broken) {
      *why = "reading fake:estop: No such device";
      return -1;
    }
    return level ? 1 : 0;
  }
};

// --- reset pulse -------------------------------------------------------------------

TEST(ResetPulse, AssertsWaitsTheDocumentedTimeAndReleases) {
  RecordingOutput line;
  std::vector<std::chrono::nanoseconds> slept;
  std::string why;
  ASSERT_TRUE(gpio::PulseReset(line, &why, gpio::kResetPulse,
                               [&](std::chrono::nanoseconds d) {
                                 // Low while it waits.
                                 EXPECT_EQ(line.levels, std::vector<bool>{true});
                                 slept.push_back(d);
                               }))
      << why;
  EXPECT_EQ(line.levels, (std::vector<bool>{true, false}));
  ASSERT_EQ(slept.size(), 1u);
  EXPECT_EQ(slept[0], std::chrono::nanoseconds(10ms));
  // With the real clock: low for at least what was asked.
  RecordingOutput timed;
  const auto t0 = std::chrono::steady_clock::now();
  ASSERT_TRUE(gpio::PulseReset(timed, &why, 2ms)) << why;
  EXPECT_GE(std::chrono::steady_clock::now() - t0, 2ms);
  EXPECT_EQ(timed.levels, (std::vector<bool>{true, false}));
  // A reset line is open drain and active low, requested released.
  const gpio::LineOptions o = gpio::ResetLineOptions("mjc reset");
  EXPECT_TRUE(o.open_drain);
  EXPECT_TRUE(o.active_low);
  EXPECT_FALSE(o.initially_active);
}

TEST(ResetPulse, AFailedAssertLeavesTheBoardReleased) {
  RecordingOutput line;
  line.fail_at = 0;
  std::string why;
  EXPECT_FALSE(gpio::PulseReset(line, &why, 1ms, [](std::chrono::nanoseconds) {}));
  EXPECT_NE(why.find("Input/output error"), std::string::npos);
  EXPECT_EQ(line.levels, std::vector<bool>{false});  // released after the failure
}

// --- emergency stop ----------------------------------------------------------------

class EmergencyStop : public ::testing::Test {
 protected:
  EmergencyStop()
      : bus_(host::InProcessBus::Create()),
        tool_(bus_->Connect()),
        board_(bus_->Connect()) {}

  // The StopAll frames the bus carried since the last call, decoded and checked.
  int Stops() {
    int n = 0;
    while (auto r = board_->Receive(0)) {
      protocol::StopAll s;
      EXPECT_EQ(r->frame.id, 0x000u);
      EXPECT_EQ(protocol::Decode(r->frame, &s), protocol::DecodeError::kOk);
      EXPECT_EQ(s.key, protocol::kStopAllKey);
      EXPECT_EQ(s.session, 0x1234);
      ++n;
    }
    return n;
  }
  host::EmergencyStopWatch Watch() {
    host::EmergencyStopConfig config;
    config.session = 0x1234;
    return host::EmergencyStopWatch(&line_, tool_.get(), config, [this] { return now_; });
  }

  std::shared_ptr<host::InProcessBus> bus_;
  std::unique_ptr<host::CanLink> tool_, board_;
  ScriptedInput line_;
  std::chrono::steady_clock::time_point now_{};
};

TEST_F(EmergencyStop, AnEdgeSendsStopAllAtOnceAndAgainWhileActive) {
  auto watch = Watch();
  std::string why;
  EXPECT_EQ(watch.Start(&why), host::EmergencyStopWatch::Step::kQuiet);
  EXPECT_EQ(watch.Poll(50ms, &why), host::EmergencyStopWatch::Step::kQuiet);
  EXPECT_EQ(Stops(), 0);
  // The press.
  line_.edges.push_back(123456789ns);
  EXPECT_EQ(watch.Poll(50ms, &why), host::EmergencyStopWatch::Step::kSent);
  EXPECT_EQ(Stops(), 1);
  EXPECT_EQ(watch.activations(), 1u);
  EXPECT_EQ(watch.last_edge(), 123456789ns);
  // Held: nothing more within 100 ms (the wait shortened to the repeat's time), then a
  // repeat every 100 ms.
  now_ += 40ms;
  EXPECT_EQ(watch.Poll(500ms, &why), host::EmergencyStopWatch::Step::kQuiet);
  EXPECT_EQ(line_.waits.back(), 60ms);
  EXPECT_EQ(Stops(), 0);
  now_ += 60ms;
  EXPECT_EQ(watch.Poll(500ms, &why), host::EmergencyStopWatch::Step::kSent);
  now_ += 100ms;
  EXPECT_EQ(watch.Poll(500ms, &why), host::EmergencyStopWatch::Step::kSent);
  EXPECT_EQ(Stops(), 2);
  // Released: no more.
  line_.level = false;
  now_ += 100ms;
  EXPECT_EQ(watch.Poll(50ms, &why), host::EmergencyStopWatch::Step::kQuiet);
  now_ += 500ms;
  EXPECT_EQ(watch.Poll(50ms, &why), host::EmergencyStopWatch::Step::kQuiet);
  EXPECT_EQ(Stops(), 0);
  EXPECT_FALSE(watch.active());
  // Pressed again: a second activation.
  line_.edges.push_back(2s);
  EXPECT_EQ(watch.Poll(50ms, &why), host::EmergencyStopWatch::Step::kSent);
  EXPECT_EQ(Stops(), 1);
  EXPECT_EQ(watch.activations(), 2u);
  EXPECT_EQ(watch.sent(), 4u);
}

TEST_F(EmergencyStop, APressedButtonAtTheStartStopsAtOnce) {
  line_.level = true;
  auto watch = Watch();
  std::string why;
  EXPECT_EQ(watch.Start(&why), host::EmergencyStopWatch::Step::kSent);
  EXPECT_EQ(Stops(), 1);
  EXPECT_EQ(watch.activations(), 1u);
}

TEST_F(EmergencyStop, ALineThatFailsEndsTheWatch) {
  auto watch = Watch();
  std::string why;
  line_.broken = true;
  EXPECT_EQ(watch.Poll(50ms, &why), host::EmergencyStopWatch::Step::kError);
  EXPECT_NE(why.find("fake:estop"), std::string::npos);
}

TEST_F(EmergencyStop, TheThreadRaisesTheToolsFlagAndStopsOnceMoreWhenTheLineFails) {
  // The button pressed at the start: the thread's first step sends, then raises.
  auto line = std::make_unique<ScriptedInput>();
  line->level = true;
  std::atomic<bool> flag{false};
  {
    host::EmergencyStopConfig config;
    config.session = 0x1234;
    host::EmergencyStopThread thread(std::move(line), bus_->Connect(), config, &flag);
    while (!thread.triggered()) std::this_thread::yield();
    EXPECT_TRUE(flag);
    EXPECT_TRUE(thread.error().empty());
  }
  EXPECT_GE(Stops(), 1);
  // A line that cannot be read: a last StopAll (session included) and the reason.
  auto broken = std::make_unique<ScriptedInput>();
  broken->broken = true;
  flag = false;
  host::EmergencyStopConfig config;
  config.session = 0x1234;
  host::EmergencyStopThread thread(std::move(broken), bus_->Connect(), config, &flag);
  while (!thread.triggered()) std::this_thread::yield();
  EXPECT_TRUE(flag);
  EXPECT_NE(thread.error().find("No such device"), std::string::npos);
  EXPECT_EQ(Stops(), 1);
}

// A link that notes, at each send, whether the tool's flag was already raised.
class FlagAtSend final : public host::CanLink {
 public:
  FlagAtSend(std::unique_ptr<host::CanLink> inner, const std::atomic<bool>* flag,
             std::vector<bool>* raised)
      : inner_(std::move(inner)), flag_(flag), raised_(raised) {}

 private:
  bool DoSend(const protocol::CanFrame& frame, std::string* why) override {
    raised_->push_back(*flag_);
    return inner_->Send(frame, why);
  }
  host::ReceiveResult DoReceive(int timeout_ms, std::string* why) override {
    return inner_->Receive(timeout_ms, why);
  }
  bool DoSetFilters(std::span<const host::IdFilter> filters, std::string* why) override {
    return inner_->SetFilters(filters, why);
  }
  std::unique_ptr<host::CanLink> inner_;
  const std::atomic<bool>* flag_;
  std::vector<bool>* raised_;
};

TEST_F(EmergencyStop, TheToolsFlagIsRaisedBeforeTheStopAllGoesOut) {
  // A board stops within a tick of the StopAll: the tool that then sees its board
  // stopped must already see that its emergency stop did it (not a fault of its own).
  auto line = std::make_unique<ScriptedInput>();
  line->level = true;
  std::atomic<bool> flag{false};
  std::vector<bool> raised;  // written by the thread's link, read once it has ended
  host::EmergencyStopConfig config;
  config.session = 0x1234;
  {
    host::EmergencyStopThread thread(
        std::move(line), std::make_unique<FlagAtSend>(bus_->Connect(), &flag, &raised),
        config, &flag);
    while (Stops() == 0) std::this_thread::yield();
    EXPECT_TRUE(thread.triggered());
  }
  ASSERT_FALSE(raised.empty());
  EXPECT_TRUE(raised.front());
}

// --- sync line ---------------------------------------------------------------------

TEST(WindowSync, EveryWindowStartIsAnEdgeRisingAtFlexions) {
  RecordingOutput line;
  host::WindowSync sync(&line);
  std::string why;
  ASSERT_TRUE(sync.Rest(&why));
  const Motion order[] = {Motion::kFlexion,   Motion::kExtension, Motion::kFlexion,
                          Motion::kExtension, Motion::kFlexion,   Motion::kExtension};
  std::uint32_t tick = 1000;
  for (const Motion m : order) {
    ASSERT_TRUE(sync.OnWindowStart({m, tick += 10000}, &why));
  }
  ASSERT_TRUE(sync.Rest(&why));  // already low after an extension: no edge
  EXPECT_EQ(line.levels,
            (std::vector<bool>{false, true, false, true, false, true, false}));
  EXPECT_EQ(sync.windows(), 6u);
  EXPECT_EQ(sync.edges(), 6u);
  // A lost WindowStart (two flexions in a row) makes no edge, and says so in the count.
  ASSERT_TRUE(sync.OnWindowStart({Motion::kFlexion, 1}, &why));
  ASSERT_TRUE(sync.OnWindowStart({Motion::kFlexion, 2}, &why));
  EXPECT_EQ(sync.windows(), 8u);
  EXPECT_EQ(sync.edges(), 7u);
}

TEST(WindowSync, TheBoardClientHandsOverWindowStartsAsTheyArrive) {
  auto bus = host::InProcessBus::Create();
  auto host_link = bus->Connect();
  auto board_link = bus->Connect();
  host::BoardClient client(host_link.get(), 3);
  std::vector<protocol::WindowStart> seen;
  client.OnWindowStart([&](const protocol::WindowStart& w) { seen.push_back(w); });
  std::string why;
  ASSERT_TRUE(board_link->Send(
      protocol::Encode(protocol::WindowStart{Motion::kExtension, 77}, 3), &why));
  ASSERT_TRUE(
      board_link->Send(protocol::Encode(protocol::WindowStart{Motion::kFlexion, 88}, 4),
                       &why));  // another node's
  ASSERT_TRUE(client.Poll(0, &why)) << why;
  ASSERT_TRUE(client.Poll(0, &why)) << why;
  ASSERT_EQ(seen.size(), 1u);
  EXPECT_EQ(seen[0].motion, Motion::kExtension);
  EXPECT_EQ(seen[0].start_tick, 77u);
}

}  // namespace
