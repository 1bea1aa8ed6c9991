// mjc param get|set|dump|restore: the board's parameters (protocol/params.h) by key, in
// the list's units. Every value asked for is checked against the list's access and
// range before anything is sent; every write is answered by the board and read back. A
// restore checks its whole file first and sends nothing when any of it is refused.
// Each command first learns who answers (one board) and that it speaks this mjc's
// protocol version.
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "commands.h"
#include "mjc/host/param_io.h"
#include "mjc/host/report.h"
#include "mjc/host/run_record.h"

namespace mjc::cli {
namespace {

struct ParamOptions {
  std::string iface;
  int node = 1;
  int timeout_ms = 1000;
};

void AddBoardOptions(CLI::App* cmd, ParamOptions* options) {
  AddIfaceOption(cmd, &options->iface);
  AddNodeOption(cmd, &options->node);
  cmd->add_option("--timeout-ms", options->timeout_ms,
                  "Wait this long (of the board's time) for each answer")
      ->check(InRange(10, 60000, "ms"))
      ->capture_default_str();
}

// A board to talk to: one board answers with the node id, and it speaks this mjc's
// protocol. Throws Failure otherwise.
class ParamBoard {
 public:
  ParamBoard(const ParamOptions& options, const std::string& command)
      : link_(OpenLink(options.iface)),
        board_(link_.get(), static_cast<std::uint8_t>(options.node)) {
    SayBusOff(board_, command, options.iface);
    IdentifyOrThrow(board_);
    std::string why;
    switch (host::CheckProtocolVersion(board_, options.timeout_ms, &why)) {
      case host::ProtocolCheck::kSame:
        return;
      case host::ProtocolCheck::kOther:
        throw Failure(why + "; nothing was sent");
      case host::ProtocolCheck::kNoAnswer:
        throw Failure(NoAnswer(board_), why);
    }
  }
  host::BoardClient& board() { return board_; }

 private:
  std::unique_ptr<host::SocketCanLink> link_;
  host::BoardClient board_;
};

// The exit status of writes that did not all go through.
Exit ExitOf(host::ParamWriteEnd end, const host::BoardClient& board) {
  return end == host::ParamWriteEnd::kNoAnswer ? NoAnswer(board) : Exit::kRefused;
}

void WarnRounding(const char* command, const std::string& where,
                  const std::vector<host::ParamSetting>& settings) {
  for (const host::ParamSetting& s : settings) {
    if (!s.exact) {
      std::fprintf(stderr, "%s: warning: %s%s\n", command, where.c_str(),
                   s.RoundingNote().c_str());
    }
  }
}

nlohmann::json ValueJson(const protocol::ParamInfo& info, std::int32_t raw) {
  return info.frac_bits == 0 ? nlohmann::json(raw)
                             : nlohmann::json(host::ParamValueOf(info, raw));
}

void AddGet(CLI::App* param) {
  static ParamOptions options;
  static std::vector<std::string> keys;
  static bool json = false;
  auto* cmd = param->add_subcommand(
      "get", "Read parameters (all of them without a KEY), in the list's units");
  AddBoardOptions(cmd, &options);
  cmd->add_option("key", keys, "Parameter keys (e.g. position_kp heartbeat_hz)");
  cmd->add_flag("--json", json,
                "One JSON object per parameter and line (value, raw, unit, access)");
  cmd->callback([] {
    std::vector<const protocol::ParamInfo*> which;
    for (const std::string& key : keys) {
      const protocol::ParamInfo* info = host::FindParam(key);
      if (info == nullptr) throw Failure(Exit::kUsage, host::UnknownParamMessage(key));
      which.push_back(info);
    }
    if (which.empty()) which = host::AllParams();
    ParamBoard board(options, "mjc param get");
    std::string why;
    const auto readings =
        host::ReadParams(board.board(), which, options.timeout_ms, &why);
    if (!readings) throw Failure(NoAnswer(board.board()), why);
    for (const host::ParamReading& r : *readings) {
      const protocol::ParamInfo& info = *r.info;
      if (json) {
        const nlohmann::json j = {{"node", options.node},
                                  {"key", info.key},
                                  {"value", ValueJson(info, r.raw)},
                                  {"unit", info.unit},
                                  {"raw", r.raw},
                                  {"access", host::ParamAccessName(info.access)}};
        std::printf("%s\n", j.dump().c_str());
      } else {
        std::printf("%-24s %-34s %-9s %s\n", info.key,
                    host::FormatParamWithUnit(info, r.raw).c_str(),
                    std::string(host::ParamAccessName(info.access)).c_str(), info.what);
      }
    }
  });
}

void AddSet(CLI::App* param) {
  static ParamOptions options;
  static std::vector<std::string> assignments;
  auto* cmd = param->add_subcommand(
      "set", "Write parameters (KEY=VALUE in the list's units), each read back");
  AddBoardOptions(cmd, &options);
  cmd->add_option("assignment", assignments, "KEY=VALUE... (e.g. position_kp=0.5)")
      ->required();
  cmd->callback([] {
    std::vector<host::ParamSetting> settings;
    for (const std::string& a : assignments) {
      std::string why;
      const auto setting = host::ParseParamAssignment(a, &why);
      if (!setting) throw Failure(Exit::kUsage, why + "; nothing was sent");
      settings.push_back(*setting);
    }
    WarnRounding("mjc param set", "", settings);
    ParamBoard board(options, "mjc param set");
    const host::ParamWriteOutcome outcome =
        host::WriteParams(board.board(), settings, options.timeout_ms);
    for (std::size_t i = 0; i < outcome.written; ++i) {
      std::printf("node %d: %s = %s\n", options.node, settings[i].info->key,
                  host::FormatParamWithUnit(*settings[i].info, settings[i].raw).c_str());
    }
    if (outcome.end != host::ParamWriteEnd::kDone) {
      const std::size_t rest = settings.size() - outcome.written - 1;
      throw Failure(ExitOf(outcome.end, board.board()),
                    outcome.why + " (" + std::to_string(outcome.written) +
                        " written before it, " + std::to_string(rest) + " not sent)");
    }
  });
}

void AddDump(CLI::App* param) {
  static ParamOptions options;
  static std::string out;
  static bool force = false;
  auto* cmd = param->add_subcommand(
      "dump", "Every parameter of a board to a JSON file (what mjc param restore reads)");
  AddBoardOptions(cmd, &options);
  cmd->add_option("-o,--out", out,
                  "Write it to this file (default: print; an existing file is refused "
                  "without --force)");
  cmd->add_flag("--force", force, "Replace the -o file if it exists");
  cmd->callback([] {
    if (!out.empty()) RefuseOverwrite(out, force, "-o");
    ParamBoard board(options, "mjc param dump");
    std::string why;
    const auto all = host::AllParams();
    const auto readings = host::ReadParams(board.board(), all, options.timeout_ms, &why);
    if (!readings) throw Failure(NoAnswer(board.board()), why);
    const std::string text = host::ParamDumpToJson(options.node, board.board().info(),
                                                   *readings, host::UtcNow())
                                 .dump(2) +
                             "\n";
    if (out.empty()) {
      std::fputs(text.c_str(), stdout);
      return;
    }
    host::WriteFile(out, text);
    std::printf("node %d: %zu parameters dumped to %s\n", options.node, readings->size(),
                out.c_str());
  });
}

void AddRestore(CLI::App* param) {
  static ParamOptions options;
  static std::string file;
  auto* cmd = param->add_subcommand(
      "restore",
      "Write a dump's parameters back to a board, the whole file checked first");
  AddBoardOptions(cmd, &options);
  cmd->add_option("file", file, "A file mjc param dump wrote")->required();
  cmd->callback([] {
    nlohmann::json j;
    try {
      j = ReadJsonObjectFile(file);
    } catch (const Failure& e) {
      throw Failure(std::string(e.what()) + "; nothing was sent");
    }
    std::string why;
    const auto settings = host::ParamRestoreFromJson(j, &why);
    if (!settings) throw Failure(file + ": " + why + "; nothing was sent");
    WarnRounding("mjc param restore", file + ": ", *settings);
    ParamBoard board(options, "mjc param restore");
    const host::ParamWriteOutcome outcome =
        host::RestoreParams(board.board(), *settings, options.timeout_ms);
    if (outcome.end != host::ParamWriteEnd::kDone) {
      std::string done;
      if (outcome.written > 0) {
        done = " (" + std::to_string(outcome.written) + " written before it)";
      }
      throw Failure(ExitOf(outcome.end, board.board()), outcome.why + done);
    }
    std::printf(
        "node %d: %zu parameters restored from %s (%zu changed, %zu already held); read "
        "back identical\n",
        options.node, settings->size(), file.c_str(), outcome.written, outcome.unchanged);
  });
}

}  // namespace

void AddParam(CLI::App& app) {
  auto* param = app.add_subcommand(
      "param", "Read, write, dump and restore a board's parameters (protocol/params.h)");
  param->require_subcommand(1);
  AddGet(param);
  AddSet(param);
  AddDump(param);
  AddRestore(param);
}

}  // namespace mjc::cli
