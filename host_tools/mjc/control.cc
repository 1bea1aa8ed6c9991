// mjc clear / mjc stop: the two commands a person at the bench needs outside a trial.
// `clear` asks each node to clear its latched fault; the board judges it on the next
// tick's sample and refuses while the cause is still there (an encoder still flagging
// an error, a joint still past its limit), so "cleared" means the cause is gone.
// `stop` ends whatever motion a node runs and leaves its bridge off.
#include <chrono>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "commands.h"
#include "mjc/host/describe.h"

namespace mjc::cli {
namespace {

using protocol::CommandCode;
using protocol::CommandOutcomeCode;

// Sends `code` to every node and prints what each answered. Once all were asked, throws
// the worst status with every failure: one silent node does not keep the others from
// their command.
void CommandEach(const std::string& iface, const std::vector<int>& nodes,
                 CommandCode code, int timeout_ms) {
  Exit worst = Exit::kOk;
  std::string failures;
  const auto fail = [&](Exit exit, const std::string& what) {
    if (static_cast<int>(exit) > static_cast<int>(worst)) worst = exit;
    failures += (failures.empty() ? "" : "; ") + what;
  };
  for (const int node : nodes) {
    auto link = OpenLink(iface);
    host::BoardClient board(link.get(), static_cast<std::uint8_t>(node));
    SayBusOff(board, code == CommandCode::kClearFaults ? "mjc clear" : "mjc stop", iface);
    const std::string who = "node " + std::to_string(node);
    std::string why;
    // A clear first learns who answers and the fault held, to say what it cleared, and
    // refuses a node two boards answer for; a stop goes at once (stopping both boards
    // of an ambiguous node is safe, and a stop must not wait).
    host::WaitEnd end{};
    if (code == CommandCode::kClearFaults &&
        !board.Identify(&end, &why, std::chrono::milliseconds(timeout_ms))) {
      fail(NoAnswer(board), why + (board.ambiguous() ? "; not cleared" : ""));
      continue;
    }
    const Fault before = board.status().fault;
    const auto outcome = board.Command(code, timeout_ms, &why);
    if (!outcome) {
      fail(NoAnswer(board), why);
      continue;
    }
    if (code == CommandCode::kStop) {
      if (*outcome != CommandOutcomeCode::kAccepted) {
        fail(Exit::kRefused,
             who + " refused to stop: " + std::string(host::OutcomeName(*outcome)));
      } else {
        std::printf("%s stopped\n", who.c_str());
      }
      continue;
    }
    if (*outcome == CommandOutcomeCode::kAccepted) {
      if (before == Fault::kNone) {
        std::printf("%s: no fault latched\n", who.c_str());
      } else {
        std::printf("%s: fault %s cleared\n", who.c_str(),
                    host::DescribeFault(before).c_str());
      }
      continue;
    }
    if (*outcome != CommandOutcomeCode::kRefusedFaultActive) {
      fail(Exit::kRefused,
           who + " refused the clear: " + std::string(host::OutcomeName(*outcome)));
      continue;
    }
    // The fault the board holds now (a clear can meet a new one); a failed poll leaves
    // the one it held before.
    (void)board.Poll(50, &why);
    fail(Exit::kRefused, who + ": fault " + host::DescribeFault(board.status().fault) +
                             " not cleared: its cause is still present");
  }
  if (worst != Exit::kOk) throw Failure(worst, failures);
}

// Registers `name`: `code` to each --node, with its options.
void AddNodeCommand(CLI::App& app, const char* name, const char* help, CommandCode code) {
  struct Options {
    std::string iface;
    std::vector<int> nodes;
    int timeout_ms = 1000;
  };
  auto options = std::make_shared<Options>();
  auto* cmd = app.add_subcommand(name, help);
  AddIfaceOption(cmd, &options->iface);
  AddNodeOption(cmd, &options->nodes, "Node ids");
  cmd->add_option("--timeout-ms", options->timeout_ms,
                  "Wait this long (of the board's time) for each board's answer")
      ->check(InRange(10, 60000, "ms"))
      ->capture_default_str();
  cmd->callback([options, code] {
    CommandEach(options->iface, options->nodes, code, options->timeout_ms);
  });
}

}  // namespace

void AddClear(CLI::App& app) {
  AddNodeCommand(app, "clear", "Clear the latched fault of boards whose cause is gone",
                 CommandCode::kClearFaults);
}

void AddStop(CLI::App& app) {
  AddNodeCommand(app, "stop", "Stop the motion of boards (bridge off)",
                 CommandCode::kStop);
}

}  // namespace mjc::cli
