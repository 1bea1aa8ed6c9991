// mjc estop: the lab's emergency-stop button on a GPIO line of the host. Each edge into
// the line's active level broadcasts a StopAll at once (identifier 0x000: every board
// latches fault 305 and disables its bridge in its next tick), again every 100 ms while
// the line stays active, and the boards' Fault frames are reported as they confirm it.
// Runs until Ctrl-C (SIGINT, SIGTERM, SIGHUP); a line or link that fails ends it with a
// last StopAll and exit 1.
#include <time.h>

#include <chrono>
#include <cstdio>
#include <random>
#include <string>

#include "commands.h"
#include "mjc/host/describe.h"
#include "mjc/host/run_record.h"
#include "mjc/protocol/codec.h"

namespace mjc::cli {
namespace {

std::chrono::nanoseconds MonotonicNow() {
  timespec t{};
  clock_gettime(CLOCK_MONOTONIC, &t);
  return std::chrono::seconds(t.tv_sec) + std::chrono::nanoseconds(t.tv_nsec);
}

// A session of its own, as the tools that send heartbeats pick one: names this watch in
// its StopAll frames (candump shows who stopped the bus).
protocol::SessionId PickSession() {
  std::random_device random;
  std::uniform_int_distribution<int> pick(1, 0xFFFF);
  return static_cast<protocol::SessionId>(pick(random));
}

}  // namespace

void AddEstop(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "estop",
      "Watch an emergency-stop button on a GPIO line: its press stops every board at "
      "once (StopAll), until Ctrl-C");
  static std::string iface;
  static EstopOptions options;
  AddIfaceOption(cmd, &iface);
  AddEstopOptions(cmd, &options, EstopDefault::kConfig, "--line");
  cmd->callback([] {
    const auto spec = LineOf(options.line);
    if (!spec) {
      throw Failure(Exit::kUsage,
                    "no emergency-stop line: give --line CHIP:LINE, or \"estop_line\" in "
                    "the config file (see mjc estop --help)");
    }
    gpio::LineOptions line_options;
    line_options.consumer = "mjc estop";
    line_options.active_low = options.active == "low";
    std::string why;
    const auto line = gpio::OpenEdgeInput(*spec, line_options, &why);
    if (!line) throw Failure(why);
    auto link = OpenLink(iface);
    // Only the boards' Fault frames: their confirmations.
    const host::IdFilter faults{
        protocol::MakeId(static_cast<std::uint8_t>(protocol::Function::kFault), 0),
        0x7F0};
    if (!link->SetFilters({&faults, 1}, &why)) throw Failure(why);
    host::EmergencyStopConfig config;
    config.session = PickSession();
    host::EmergencyStopWatch watch(line.get(), link.get(), config);
    const std::atomic<bool>& stop = StopOnSignals();
    std::fprintf(stderr,
                 "mjc estop: watching %s (active %s) for %s; its press stops every "
                 "board; Ctrl-C ends\n",
                 line->name().c_str(), options.active.c_str(), iface.c_str());

    std::uint64_t shown = 0;
    bool was_active = false;
    const auto report = [&](host::EmergencyStopWatch::Step step) {
      if (step == host::EmergencyStopWatch::Step::kError) {
        // The button can no longer be heard: stop everything once more if the bus
        // takes it, and say so.
        std::string ignored;
        protocol::StopAll last;
        last.session = config.session;
        const bool sent =
            link->Send(protocol::Encode(last, protocol::kEveryNode), &ignored);
        throw Failure(why + (sent ? "; every board was told to stop" : ""));
      }
      if (watch.activations() != shown) {
        shown = watch.activations();
        if (watch.last_edge().count() != 0) {
          const double after_ms = std::chrono::duration<double, std::milli>(
                                      MonotonicNow() - watch.last_edge())
                                      .count();
          std::printf(
              "%s emergency stop: %s active: StopAll sent on %s %.2f ms after "
              "the edge\n",
              host::UtcNow().c_str(), line->name().c_str(), iface.c_str(), after_ms);
        } else {
          std::printf("%s emergency stop: %s active at the start: StopAll sent on %s\n",
                      host::UtcNow().c_str(), line->name().c_str(), iface.c_str());
        }
      }
      if (was_active && !watch.active()) {
        std::printf("%s %s released (%llu StopAll frames sent so far)\n",
                    host::UtcNow().c_str(), line->name().c_str(),
                    static_cast<unsigned long long>(watch.sent()));
      }
      was_active = watch.active();
      std::fflush(stdout);
    };
    report(watch.Start(&why));
    while (!stop) {
      // Short waits, so that the boards' confirmations are shown as they come; an edge
      // ends a wait at once.
      report(watch.Poll(std::chrono::milliseconds(20), &why));
      for (;;) {
        const host::ReceiveResult r = link->Receive(0, &why);
        if (r.failed()) throw Failure(why);
        if (!r) break;
        protocol::FaultEvent e;
        if (protocol::Decode(r->frame, &e) != protocol::DecodeError::kOk ||
            e.fault != Fault::kEmergencyStop) {
          continue;
        }
        std::printf("%s node %u stopped: fault %s\n", host::UtcNow().c_str(),
                    protocol::NodeOf(r->frame.id), host::DescribeFault(e.fault).c_str());
        std::fflush(stdout);
      }
    }
    std::fprintf(stderr, "mjc estop: %llu emergency stops, %llu StopAll frames sent\n",
                 static_cast<unsigned long long>(watch.activations()),
                 static_cast<unsigned long long>(watch.sent()));
  });
}

}  // namespace mjc::cli
