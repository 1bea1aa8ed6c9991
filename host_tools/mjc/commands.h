// The mjc subcommands and what they share. Each Add* registers its subcommand (options
// and a callback) on the CLI11 app. A callback that returns has succeeded (exit 0); one
// that fails throws, Failure with its exit status or any std::exception (kFailure), and
// main prints "mjc <subcommand>: <what>" on one line.
#pragma once

#include <signal.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <csignal>
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <string>

#include "mjc/host/board_client.h"
#include "mjc/host/can_link.h"
#include "mjc/protocol/can_frame.h"

namespace mjc::cli {

// Slowest trial or sweep the board accepts at its 10 kHz tick: a window (half a cycle)
// must fit the 16-bit tick offsets of its WindowTicks frame (65,535 ticks, 76.3 mHz);
// slower ones are refused with kDetailWindowTooLong.
inline constexpr double kMinFrequencyHz = 0.08;
inline constexpr double kMaxFrequencyHz = 5.0;

// The exit status of every subcommand. Stable: scripts test them.
enum class Exit : int {
  kOk = 0,
  kFailure = 1,   // on this side: bad or unwritable file, interface, link, unusable fit
  kUsage = 2,     // bad command line
  kNoAnswer = 3,  // a node did not answer, went silent or did not finish in time
  kRefused = 4,   // the board refused, holds no calibration, or did not keep it
  kFaulted = 5,   // the board faulted while carrying it out
  kStopped = 6,   // the motion ended before its end: interrupted here (a signal; the
                  // board was told to stop) or stopped by another tool
};

// The footer of every --help.
inline constexpr const char* kExitStatusHelp =
    "Exit status: 0 done; 1 failed on this side (input or output file, interface, "
    "link, unusable fit, gnuplot); 2 bad command line; 3 a node did not answer, went "
    "silent or did not finish in time; 4 the board refused, holds no calibration or "
    "did not keep what was sent; 5 the board faulted; 6 the motion was stopped before "
    "its end (interrupted: the board was stopped and what arrived is saved; or stopped "
    "by another tool).";

class Failure : public std::runtime_error {
 public:
  Failure(Exit exit, const std::string& what) : std::runtime_error(what), exit_(exit) {}
  explicit Failure(const std::string& what) : Failure(Exit::kFailure, what) {}
  Exit exit() const { return exit_; }

 private:
  Exit exit_;
};

// The status of a request to `board` that got no answer: kFailure when this side's
// link failed, kNoAnswer when the board stayed silent.
inline Exit NoAnswer(const host::BoardClient& board) {
  return board.link_failed() ? Exit::kFailure : Exit::kNoAnswer;
}

// --iface, defaulting to vcan0.
inline CLI::Option* AddIfaceOption(CLI::App* cmd, std::string* iface,
                                   const char* help = "CAN interface") {
  *iface = "vcan0";
  return cmd->add_option("--iface", *iface, help)->capture_default_str();
}

// --node into an int (one node) or a std::vector<int> (several), checked against the
// protocol's node range.
template <class T>
CLI::Option* AddNodeOption(CLI::App* cmd, T* node, const char* help = "Node id") {
  return cmd->add_option("--node", *node, help)
      ->check(CLI::Range(int{protocol::kMinNode}, int{protocol::kMaxNode}))
      ->capture_default_str();
}

// The raw CAN link on `iface`; throws Failure naming the interface when it cannot open.
inline std::unique_ptr<host::SocketCanLink> OpenLink(const std::string& iface) {
  std::string why;
  auto link = host::SocketCanLink::Open(iface, &why);
  if (!link) throw Failure(why);
  return link;
}

// Has `board`'s waits say on stderr, the moment they see it, that `iface`'s controller
// reported bus-off: frames are lost until it recovers, and a board on a failing bus
// stops with kCanBusOff (the tool then reports the fault itself).
inline void SayBusOff(host::BoardClient& board, const std::string& command,
                      const std::string& iface) {
  board.OnBusOff([command, iface](std::uint64_t total) {
    std::fprintf(stderr,
                 "\n%s: %s: the CAN controller reported bus-off (%llu since start): "
                 "frames are lost until it recovers\n",
                 command.c_str(), iface.c_str(), static_cast<unsigned long long>(total));
  });
}

namespace detail {
inline std::atomic<bool> g_stop{false};
inline void OnStopSignal(int) { g_stop = true; }
}  // namespace detail

// Makes SIGINT, SIGTERM and SIGHUP (Ctrl-C, kill, a closed terminal) end a
// long-running command cleanly — a motion it started stopped, files flushed, counts
// printed: the returned flag turns true when one arrives. Without SA_RESTART, so a
// blocking read (a prompt) returns at once.
inline const std::atomic<bool>& StopOnSignals() {
  struct sigaction action = {};
  action.sa_handler = detail::OnStopSignal;
  sigemptyset(&action.sa_mask);
  for (const int signal : {SIGINT, SIGTERM, SIGHUP}) sigaction(signal, &action, nullptr);
  return detail::g_stop;
}

// Stops the motion `board` runs, confirmed by the board, whatever interrupted the
// client's waits: "node N stopped", or why it could not be confirmed.
inline std::string StopMotion(host::BoardClient& board) {
  board.SetInterrupt(nullptr);
  std::string why;
  const auto outcome = board.Command(protocol::CommandCode::kStop, 1000, &why);
  const std::string who = "node " + std::to_string(board.node());
  if (outcome && *outcome == protocol::CommandOutcomeCode::kAccepted)
    return who + " stopped";
  return who + " did not confirm the stop (" + (outcome ? "refused" : why) +
         "); it stops by itself once this tool's heartbeat stays away";
}

void AddSim(CLI::App& app);
void AddLog(CLI::App& app);
void AddCal(CLI::App& app);
void AddCalibrate(CLI::App& app);
void AddBusload(CLI::App& app);
void AddTrial(CLI::App& app);
void AddReport(CLI::App& app);
void AddMonitor(CLI::App& app);
void AddClear(CLI::App& app);
void AddStop(CLI::App& app);

}  // namespace mjc::cli
