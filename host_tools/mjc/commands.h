// The mjc subcommands and what they share. Each Add* registers its subcommand (options
// and a callback) on the CLI11 app. A callback that returns has succeeded (exit 0); one
// that fails throws, Failure with its exit status or any std::exception (kFailure), and
// main prints "mjc <subcommand>: <what>" on one line.
#pragma once

#include <signal.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include "mjc/gpio/line_spec.h"
#include "mjc/host/board_client.h"
#include "mjc/host/can_link.h"
#include "mjc/host/config.h"
#include "mjc/host/emergency_stop.h"
#include "mjc/host/hand.h"
#include "mjc/host/report.h"
#include "mjc/host/run_record.h"
#include "mjc/protocol/can_frame.h"
#include "mjc/strict_json.h"

namespace mjc::cli {

// Slowest trial or sweep the board accepts at its 10 kHz tick: a window (half a cycle)
// must fit the 16-bit tick offsets of its WindowTicks frame (65,535 ticks, 76.3 mHz);
// slower ones are refused with kDetailWindowTooLong.
inline constexpr double kMinFrequencyHz = 0.08;
inline constexpr double kMaxFrequencyHz = 5.0;

// The exit status of every subcommand. Stable: scripts test them.
enum class Exit : int {
  kOk = 0,
  kFailure = 1,     // on this side: bad or unwritable file, interface, link, unusable fit
  kUsage = 2,       // bad command line
  kNoAnswer = 3,    // a node did not answer, went silent or did not finish in time
  kRefused = 4,     // the board refused, holds no calibration, or did not keep it
  kFaulted = 5,     // the board faulted while carrying it out
  kStopped = 6,     // the motion ended before its end: interrupted here (a signal; the
                    // board was told to stop) or stopped by another tool
  kAmbiguous = 7,   // two boards answer with one node id, or one frame showed a sign of
                    // it: nothing was done to it (a motion already running was stopped)
  kNotUpdated = 8,  // mjc flash: a board caught for an update does not run the new
                    // image (named; usually left in its bootloader, which waits for an
                    // image: run mjc flash again)
};

// The footer of every --help.
inline constexpr const char* kExitStatusHelp =
    "Exit status: 0 done; 1 failed on this side (input or output file, interface, "
    "link, GPIO line, unusable fit, gnuplot); 2 bad command line; 3 a node did not "
    "answer, went silent or did not finish in time; 4 the board refused, holds no "
    "calibration or did not keep what was sent; 5 the board faulted; 6 the motion was "
    "stopped before its end (interrupted: the board was stopped and what arrived is "
    "saved; stopped by another tool; or by the emergency stop); 7 two boards answer "
    "with one node id, or a frame showed a sign of it (nothing was done to it; give "
    "each board its own id); 8 mjc flash: "
    "a board was not updated (named; it waits "
    "in its bootloader: run mjc flash again).\n"
    "Defaults: --iface from MJC_IFACE, else the config file's \"iface\", else vcan0; "
    "--node from its \"node\", else 1; --joint NAME is looked up in --hand FILE, else "
    "in its \"hand\" (hands/README.md; the hand's \"iface\" then wins over "
    "MJC_IFACE and the config's); GPIO lines "
    "(CHIP:LINE) from its \"estop_line\", "
    "\"estop_active\", \"sync_line\" and \"reset_lines\". The config file is "
    "$MJC_CONFIG, else ~/.config/mjc/config.json (JSON: {\"iface\": \"can0\", "
    "\"node\": 2}; an unknown key is an error). The command line wins.\n"
    "No CAN interface on this machine? scripts/kernel-vm shell starts a virtual machine "
    "with vcan0 and this tree mounted.";

class Failure : public std::runtime_error {
 public:
  Failure(Exit exit, const std::string& what) : std::runtime_error(what), exit_(exit) {}
  explicit Failure(const std::string& what) : Failure(Exit::kFailure, what) {}
  Exit exit() const { return exit_; }

 private:
  Exit exit_;
};

// The status of a request to `board` that got no answer: kFailure when this side's
// link failed, kAmbiguous when two boards answer, kNoAnswer when the board stayed
// silent.
inline Exit NoAnswer(const host::BoardClient& board) {
  if (board.link_failed()) return Exit::kFailure;
  return board.ambiguous() ? Exit::kAmbiguous : Exit::kNoAnswer;
}

// The defaults the command line starts from (main loads them before the subcommands
// are added): the config file's, with MJC_IFACE over its interface.
host::ToolConfig& Defaults();
// Loads Defaults() from the config file. A file that cannot be used stops every
// command but --help, -h and --version: false, with the reason in *why.
bool LoadDefaults(int argc, char** argv, std::string* why);

// --iface, defaulting to MJC_IFACE, the config file's, or vcan0.
// --- Hands: --hand FILE and --joint NAME (hands/README.md) ---------------------------

// What a command's --node, --hand, --joint (and, where it has them, --iface and --robot)
// were bound to, for ResolveJoints after parsing. One per subcommand, kept by
// TargetsOf.
struct NodeTargets {
  CLI::Option* node_option = nullptr;
  CLI::Option* hand_option = nullptr;
  CLI::Option* iface_option = nullptr;
  std::string* iface = nullptr;
  CLI::Option* robot_option = nullptr;
  std::string* robot = nullptr;
  bool several = false;  // the command takes several nodes
  std::string hand_path;
  std::vector<std::string> joints;
  // The node ids chosen, into the command's --node variable.
  std::function<void(const std::vector<int>&)> set_nodes;
  // After parsing: the hand given (or the config file's, when --joint named a joint)
  // and the joints chosen from it, in its order.
  std::optional<host::Hand> hand;
  std::vector<host::HandJoint> chosen;
};
inline NodeTargets& TargetsOf(const CLI::App* cmd) {
  static std::map<const CLI::App*, NodeTargets> targets;  // nodes stay where they are
  return targets[cmd];
}

// Resolves --hand and --joint into the command's node ids (and --iface, --robot),
// after parsing and before the command runs. Throws Failure: kUsage for --node with
// --joint or --hand, an unknown joint (the hand's joints listed), --hand alone where
// one node is taken, --joint without a hand, --robot naming another file than the
// joint's description; kFailure for a hand file that is refused.
void ResolveJoints(NodeTargets& t);

// --iface, defaulting to MJC_IFACE, the config file's, or vcan0 (with --hand, the hand
// file's "iface" unless --iface is given).
inline CLI::Option* AddIfaceOption(CLI::App* cmd, std::string* iface,
                                   const char* help = "CAN interface") {
  *iface = Defaults().iface.value_or("vcan0");
  NodeTargets& t = TargetsOf(cmd);
  t.iface = iface;
  t.iface_option = cmd->add_option("--iface", *iface, help)->capture_default_str();
  return t.iface_option;
}

// A number within [lo, hi] (inclusive), for options and each value of a vector option:
// a refusal names the value and the range ("--amplitudes: 100 is outside 1..90 °").
inline CLI::Validator InRange(double lo, double hi, const std::string& unit = "") {
  const auto text = [](double v) {
    char out[32];
    std::snprintf(out, sizeof out, "%g", v);
    return std::string(out);
  };
  const std::string range = text(lo) + ".." + text(hi) +
                            (unit.empty()  ? ""
                             : unit == "°" ? unit
                                           : " " + unit);
  return CLI::Validator(
      [=](std::string& value) -> std::string {
        char* end = nullptr;
        const double v = std::strtod(value.c_str(), &end);
        if (value.empty() || end == nullptr || *end != '\0' || !std::isfinite(v)) {
          return "'" + value + "' is not a number";
        }
        if (v < lo || v > hi) return value + " is outside " + range;
        return std::string();
      },
      "in " + range);
}

// --node into an int (one node) or a std::vector<int> (several), checked against the
// protocol's node range; its default the config file's node, else 1.
// With `by_joint` (every mjc command that talks to boards), also --hand FILE and
// --joint NAME (repeatable where T is a vector; --hand alone then means every joint of
// the hand), resolved into *node once the command line is parsed (ResolveJoints).
template <class T>
CLI::Option* AddNodeOption(CLI::App* cmd, T* node, const char* help = "Node id",
                           bool by_joint = true) {
  const int fallback = Defaults().node.value_or(1);
  constexpr bool kOne = std::is_same_v<T, int>;
  if constexpr (kOne) {
    *node = fallback;
  } else {
    *node = {fallback};
  }
  CLI::Option* option = cmd->add_option("--node", *node, help)
                            ->check(InRange(protocol::kMinNode, protocol::kMaxNode))
                            ->capture_default_str();
  if (!by_joint) return option;
  NodeTargets& t = TargetsOf(cmd);
  t.node_option = option;
  t.several = !kOne;
  t.set_nodes = [node](const std::vector<int>& nodes) {
    if constexpr (kOne) {
      *node = nodes.front();
    } else {
      *node = nodes;
    }
  };
  t.hand_option =
      cmd->add_option("--hand", t.hand_path,
                      std::string("Hand file (hands/*.json): --joint names its joints") +
                          (kOne ? "" : "; alone, every joint of the hand") +
                          "; its \"iface\" is the default --iface");
  cmd->add_option("--joint", t.joints,
                  std::string(kOne ? "The joint to talk to, by its name in --hand (or "
                                     "the config file's \"hand\"), instead of --node"
                                   : "A joint to talk to, by its name in --hand (or the "
                                     "config file's \"hand\"), instead of --node; "
                                     "repeat for several"))
      ->type_name("NAME");
  cmd->parse_complete_callback([cmd] { ResolveJoints(TargetsOf(cmd)); });
  return option;
}

// A command's --robot (a robot description's path), which --joint fills in with the
// joint's description; a --robot given with --joint must name the same file.
inline void JointSuppliesRobot(CLI::App* cmd, CLI::Option* robot_option,
                               std::string* robot) {
  NodeTargets& t = TargetsOf(cmd);
  t.robot_option = robot_option;
  t.robot = robot;
}

// --frequency-hz of a trial or sweep, within what the board accepts (kMinFrequencyHz,
// kMaxFrequencyHz).
inline CLI::Option* AddFrequencyOption(CLI::App* cmd, double* frequency_hz,
                                       const char* help) {
  return cmd->add_option("--frequency-hz", *frequency_hz, help)
      ->check(InRange(kMinFrequencyHz, kMaxFrequencyHz, "Hz"))
      ->capture_default_str();
}

// --out and --force of a command that writes a run's folder (see host::OutputFolder).
struct OutputOptions {
  std::string out;
  bool force = false;
};
inline void AddOutputOptions(CLI::App* cmd, OutputOptions* options,
                             const std::string& base) {
  cmd->add_option("--out", options->out,
                  "Output folder (default: a new " + base +
                      "/<UTC time>/; an existing non-empty one is refused without "
                      "--force)");
  cmd->add_flag("--force", options->force,
                "Write into an existing --out folder, replacing an earlier run's files");
}

// The folder a run of `tool` ("mjc trial") writes into: host::PrepareOutputFolder with
// --out and --force, a new one under `base` (the base AddOutputOptions named) without
// --out. Said on stderr before anything is written; a folder that cannot be used is a
// Failure.
inline std::filesystem::path PrepareOutputs(const char* tool,
                                            const OutputOptions& options,
                                            const std::string& base,
                                            const std::vector<std::string>& outputs) {
  host::OutputFolder folder;
  try {
    folder = host::PrepareOutputFolder(options.out, base, options.force, outputs);
  } catch (const std::exception& e) {
    throw Failure(e.what());
  }
  std::fprintf(stderr, "%s: writing to %s/%s\n", tool, folder.path.c_str(),
               folder.chosen ? " (a new folder)" : "");
  return folder.path;
}

// An output file a command would replace (mjc param dump -o, mjc cal download --out):
// refused before anything is asked of a board unless --force, as a run's folder is
// (host::PrepareOutputFolder). A folder is refused even with --force.
inline void RefuseOverwrite(const std::string& path, bool force, const char* option) {
  std::error_code error;
  if (std::filesystem::is_directory(path, error)) {
    throw Failure(path + " is a folder: give " + option + " a file name");
  }
  if (!force && std::filesystem::exists(path, error)) {
    throw Failure(path +
                  " exists: nothing is replaced without --force (or choose another " +
                  option + ")");
  }
}

// The JSON object in the file at `path`, read strictly (mjc/strict_json.h: a key given
// twice or anything after the object refused); throws Failure naming the file.
inline nlohmann::json ReadJsonObjectFile(const std::string& path) {
  const auto text = host::ReadFileText(path);
  if (!text) throw Failure("cannot read " + path);
  try {
    return strict::ParseObject<nlohmann::json>(*text, path);
  } catch (const std::exception& e) {
    throw Failure(e.what());
  }
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
// A progress line on stderr and its end: on a terminal, one line rewritten in place
// ("\r"), and a message that follows starts on a line of its own (no empty line when
// none was open); into a file or a pipe, plain lines, one each time `milestone` changes
// (the line itself by default: a line whose only change is a running clock is not
// repeated into a log). A stderr that is closed (a pipe whose reader went) loses the
// line and nothing else: SIGPIPE is ignored (main) and the EPIPE is not an error here.
inline bool& ProgressOpen() {
  static bool open = false;
  return open;
}
inline void Progress(const std::string& line, const std::string& milestone = "") {
  static const bool terminal = ::isatty(STDERR_FILENO) == 1;
  if (terminal) {
    std::fprintf(stderr, "\r%s   ", line.c_str());
    ProgressOpen() = true;
    return;
  }
  static std::string last;
  const std::string& now = milestone.empty() ? line : milestone;
  if (now == last) return;
  last = now;
  std::fprintf(stderr, "%s\n", line.c_str());
}
inline void EndProgress() {
  if (ProgressOpen()) std::fputc('\n', stderr);
  ProgressOpen() = false;
}

inline void SayBusOff(host::BoardClient& board, const std::string& command,
                      const std::string& iface) {
  board.OnBusOff([command, iface](std::uint64_t total) {
    EndProgress();
    std::fprintf(stderr,
                 "%s: %s: the CAN controller reported bus-off (%llu since start): "
                 "frames are lost until it recovers\n",
                 command.c_str(), iface.c_str(), static_cast<unsigned long long>(total));
  });
}

// The run.json end for a tool's exit status.
inline const char* OutcomeOf(Exit exit) {
  switch (exit) {
    case Exit::kOk:
      return "completed";
    case Exit::kNoAnswer:
      return "no_answer";
    case Exit::kRefused:
      return "refused";
    case Exit::kFaulted:
      return "faulted";
    case Exit::kStopped:
      return "interrupted";
    case Exit::kAmbiguous:
      return "ambiguous";
    case Exit::kFailure:
    case Exit::kUsage:
    case Exit::kNotUpdated:
      break;
  }
  return "failed";
}

namespace detail {
inline std::atomic<bool> g_stop{false};
inline void OnStopSignal(int) { g_stop = true; }
}  // namespace detail

// The flag StopOnSignals returns, for what else ends a command's waits the same way
// (the emergency-stop watch).
inline std::atomic<bool>& StopFlag() { return detail::g_stop; }

// The signals that ask a command to end (Ctrl-C, kill, a closed terminal, Ctrl-\\).
inline constexpr int kStopSignals[] = {SIGINT, SIGTERM, SIGHUP, SIGQUIT};

// Makes SIGINT, SIGTERM, SIGHUP and SIGQUIT end a long-running command cleanly — a
// motion it started stopped, what arrived kept, counts printed, exit 6 — where their
// default would kill it mid-motion (SIGQUIT with a core dump, exit 131): the returned
// flag turns true when one arrives. Without SA_RESTART, so a blocking read (a prompt)
// returns at once. (SIGKILL cannot be caught: the board stops by itself when the
// heartbeat stays away, and every record is already in the files.)
inline const std::atomic<bool>& StopOnSignals() {
  struct sigaction action = {};
  action.sa_handler = detail::OnStopSignal;
  sigemptyset(&action.sa_mask);
  for (const int signal : kStopSignals) sigaction(signal, &action, nullptr);
  return detail::g_stop;
}

// Stops the motion `board` runs, confirmed by the board, whatever interrupted the
// client's waits: "node N stopped", or why it could not be confirmed.
inline std::string StopMotion(host::BoardClient& board) {
  board.SetInterrupt(nullptr);
  board.ReleaseMotion();  // whatever runs is stopped, ours or not
  std::string why;
  const auto outcome = board.Command(protocol::CommandCode::kStop, 1000, &why);
  const std::string who = "node " + std::to_string(board.node());
  if (outcome && *outcome == protocol::CommandOutcomeCode::kAccepted)
    return who + " stopped";
  if (board.ambiguous())
    return who + "'s boards were sent a stop (two answer: unconfirmed)";
  return who + " did not confirm the stop (" + (outcome ? "refused" : why) +
         "); it stops by itself once this tool's heartbeat stays away";
}

// Listens to `board` until it has shown who it is (BoardClient::Identify), before a
// command acts on it: throws Failure when it is silent (kNoAnswer) or two boards answer
// with its id (kAmbiguous).
inline void IdentifyOrThrow(host::BoardClient& board, std::chrono::milliseconds silence =
                                                          host::Patience{}.silence) {
  host::WaitEnd end{};
  std::string why;
  if (board.Identify(&end, &why, silence)) return;
  switch (end) {
    case host::WaitEnd::kAmbiguous:
      throw Failure(Exit::kAmbiguous, why + "; nothing was done");
    case host::WaitEnd::kLinkFailed:
      throw Failure(why);
    case host::WaitEnd::kInterrupted:
      throw Failure(Exit::kStopped, "interrupted before anything was done");
    case host::WaitEnd::kSilent:
    case host::WaitEnd::kBoardTime:
    case host::WaitEnd::kWrongMotion:  // nothing was started: not while identifying
      break;
  }
  throw Failure(Exit::kNoAnswer, why);
}

// mjc list's scan and table (or JSON lines) of every board on `iface`; mjc flash --info
// shows the same. Throws Failure: nothing heard (kNoAnswer), two boards behind one id
// (kAmbiguous, after the table), the link, a signal.
// With `hand`, then each joint present or missing, the boards the hand does not have and
// those of another build (host::CheckHand); a joint missing is a Failure (kNoAnswer).
void ListBoards(const std::string& iface, int silence_ms, bool json,
                const host::Hand* hand = nullptr);

// --- GPIO lines (README: GPIO lines) ---------------------------------------------

// A CHIP:LINE option's check ("none" too, where `none` allows it: no line).
inline CLI::Validator LineSpecCheck(bool none) {
  return CLI::Validator(
      [none](std::string& value) -> std::string {
        if (none && value == "none") return std::string();
        std::string why;
        return gpio::ParseLineSpec(value, &why) ? std::string() : why;
      },
      none ? "CHIP:LINE or none" : "CHIP:LINE");
}

// The spec of a checked option's value; nullopt for "none" or empty.
inline std::optional<gpio::LineSpec> LineOf(const std::string& value) {
  std::string why;
  if (value.empty() || value == "none") return std::nullopt;
  return gpio::ParseLineSpec(value, &why);
}

// --estop-line and --estop-active: the emergency-stop button a command watches while
// it runs. kConfig: the config file's "estop_line" is the default ("none" leaves it
// unwatched: trial, calibrate); kGiven: watched only when given (monitor). mjc estop
// names its option --line (kConfig; "none" means nothing there).
enum class EstopDefault : std::uint8_t { kConfig, kGiven };
struct EstopOptions {
  std::string line;
  std::string active = "high";
};
inline void AddEstopOptions(CLI::App* cmd, EstopOptions* options, EstopDefault from,
                            const char* name = "--estop-line") {
  const host::ToolConfig& config = Defaults();
  const bool from_config = from == EstopDefault::kConfig;
  const bool none = from_config && std::string_view(name) == "--estop-line";
  if (from_config && config.estop_line) options->line = config.estop_line->text();
  if (config.estop_active_low)
    options->active = *config.estop_active_low ? "low" : "high";
  cmd->add_option(name, options->line,
                  std::string("Emergency-stop input CHIP:LINE (a chip's name, path, "
                              "label or number; a line's offset or name): its edge into "
                              "the active level sends StopAll to every node at once") +
                      (none ? "; none: not watched" : ""))
      ->check(LineSpecCheck(none))
      ->capture_default_str();
  cmd->add_option("--estop-active", options->active,
                  "The emergency-stop line's active level (pressed, or a broken wire)")
      ->check(CLI::IsMember({"high", "low"}))
      ->capture_default_str();
}

// Starts watching options.line on a thread (nullptr when there is none), on a link of
// its own on `iface`: a StopAll raises `raise` (the command's stop flag, ending its
// waits; null for none). Throws Failure naming the line when it cannot be opened (no
// chip, no line, held by another program).
inline std::unique_ptr<host::EmergencyStopThread> StartEstop(const EstopOptions& options,
                                                             const std::string& iface,
                                                             const std::string& consumer,
                                                             protocol::SessionId session,
                                                             std::atomic<bool>* raise) {
  const auto spec = LineOf(options.line);
  if (!spec) return nullptr;
  gpio::LineOptions line_options;
  line_options.consumer = consumer;
  line_options.active_low = options.active == "low";
  std::string why;
  auto line = gpio::OpenEdgeInput(*spec, line_options, &why);
  if (!line) throw Failure("emergency-stop line: " + why);
  host::EmergencyStopConfig config;
  config.session = session;
  return std::make_unique<host::EmergencyStopThread>(std::move(line), OpenLink(iface),
                                                     config, raise);
}

// What a command that moves a board sets up once its client is open: a bus-off said at
// once, its waits ended by SIGINT, SIGTERM or SIGHUP (StopOnSignals), and the
// emergency-stop watch on options.line (StartEstop), whose StopAll ends them too.
// Returns the watch (nullptr without a line); StopFlag() tells whether they ended.
inline std::unique_ptr<host::EmergencyStopThread> GuardMotion(
    host::BoardClient& board, const std::string& command, const std::string& iface,
    const EstopOptions& options) {
  SayBusOff(board, command, iface);
  board.SetInterrupt(&StopOnSignals());
  return StartEstop(options, iface, command, board.session(), &StopFlag());
}

// "emergency stop on gpiochip0:estop: every board was told to stop", or the watch's
// failure.
inline std::string EstopWhat(const host::EmergencyStopThread& estop) {
  return (estop.error().empty()
              ? "emergency stop on " + estop.line_name()
              : "the emergency-stop line failed (" + estop.error() + ")") +
         ": every board was told to stop";
}

// After an emergency stop during a motion of `board`: waits (1 s of its time at most,
// or its silence) for the board to report the emergency-stop fault, and says so.
inline std::string ConfirmEmergencyStop(host::BoardClient& board,
                                        const host::EmergencyStopThread& estop) {
  board.SetInterrupt(nullptr);
  const std::string who = "node " + std::to_string(board.node());
  const std::string what = EstopWhat(estop);
  host::WaitEnd end{};
  std::string why;
  const std::chrono::milliseconds second{1000};
  if (board.Await([&] { return board.status().fault == Fault::kEmergencyStop; },
                  {second, second}, &end, &why)) {
    return what + "; " + who + " stopped (fault 305, emergency stop: mjc clear --node " +
           std::to_string(board.node()) + " releases it)";
  }
  return what + "; " + who + " did not confirm it (" + why + ")";
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
void AddList(CLI::App& app);
void AddFlash(CLI::App& app);

void AddEstop(CLI::App& app);
void AddReset(CLI::App& app);
void AddParam(CLI::App& app);

}  // namespace mjc::cli
