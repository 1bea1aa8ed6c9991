// run.json: what a run of mjc trial or mjc calibrate was, written beside its data so
// the data is never read without it — which board (its BoardInfo) with which
// calibration, the protocol and its settings, who and when, and how it ended — and the
// run's output folder, which never overwrites another run's.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "mjc/host/calibration_io.h"
#include "mjc/protocol/messages.h"

namespace mjc::host {

// How a run ended. "running" is written when it starts: a run.json that still says so
// belongs to a tool that died (SIGKILL, power loss) before it could say more.
struct RunEnd {
  std::string outcome = "running";  // completed, interrupted, stopped, faulted,
                                    // no_answer, refused, ambiguous, failed, running,
                                    // emergency_stop (mjc estop's StopAll, a button)
  std::optional<int> fault_code;    // with "faulted": the board's fault code
  std::string message;              // why, in the tool's words ("" when completed)
};

inline constexpr std::string_view kRunOutcomes[] = {
    "completed", "interrupted", "stopped", "faulted", "no_answer",
    "refused",   "ambiguous",   "failed",  "running", "emergency_stop"};

struct RunRecord {
  std::string command;  // "trial" or "calibrate"
  int node = 0;
  std::string iface;
  std::optional<protocol::BoardInfo> board;     // the board's BoardInfo, if it sent one
  std::optional<BoardCalibration> calibration;  // read from the board at the start
  // The robot description the run used (calibrate --robot): {"path": the file as
  // given, "description": its content, as read}; null without one. The content, not
  // only the path: the file may change or go after the run.
  nlohmann::json robot;
  // Every parameter the board held when the run started (protocol/params.h's keys, in
  // the list's units): the velocity window, the attachment's priors, the torque limit
  // and the rest that shape its estimate. Null when they could not be read.
  nlohmann::json params;
  // This process, while the run goes on: a run.json still saying "running" whose
  // process is gone belongs to a host that died without a word (RunStillGoing).
  std::optional<long> pid;
  std::optional<std::string> subject;  // as the operator gave it
  std::string protocol;                // repeatability, amplitude, sweep
  std::vector<double> amplitudes_deg;  // a trial's each; a sweep's final one
  double frequency_hz = 0;
  int repetitions = 0;  // per trial; a sweep's cycles
  double rest_s = 0;
  std::string started_utc;  // ISO 8601, UTC
  std::string host;         // this machine's name
  std::string mjc;          // mjc's build (git describe)
  RunEnd end;
};

nlohmann::json RunRecordToJson(const RunRecord& record);
// Strict: every key known (named with the nearest known one otherwise), every value of
// its type. nullopt with the reason naming the key.
std::optional<RunRecord> RunRecordFromJson(const nlohmann::json& json, std::string* why);

// Writes dir/run.json (replacing it whole, ReplaceFile: a run rewrites its own at each
// change of its state, and a process killed mid-write leaves the previous one); throws
// std::runtime_error naming the file when it cannot.
void WriteRunRecord(const RunRecord& record, const std::filesystem::path& dir);
// dir/run.json: nullopt with *why empty when there is none (a folder from before
// run.json), or with the reason when it is unreadable or refused.
std::optional<RunRecord> ReadRunRecord(const std::filesystem::path& dir,
                                       std::string* why);

// For a run.json that still says "running": whether its process is still there (the
// same host, its pid alive and an mjc). False: the host died without a word (SIGKILL,
// a crash, a power cut), and its files hold what it had received.
bool RunStillGoing(const RunRecord& record);

// The "robot" of run.json for a description read from `path` (its text): {"path",
// "description"}; throws std::runtime_error when the text is not JSON.
nlohmann::json RobotRecord(const std::string& path, const std::string& text);

// Every parameter `board` holds (param_io.h's ReadParams of the whole list), as
// run.json's "params": {key: value in the list's units}; null with *why when a read
// went unanswered.
nlohmann::json ReadBoardParams(BoardClient& board, std::string* why);

// A run that ended before anything moved (no interface, no board, a refusal) leaves
// no folder behind for a lab to wonder about: the files named in `outputs` are removed
// from `dir` (with run.json's temporary), and `dir` itself when it is then empty and
// `created` (this run made it). Errors are ignored: this is tidying, the failure is
// said already.
void DiscardUnstartedRun(const std::filesystem::path& dir,
                         const std::vector<std::string>& outputs, bool created);

// A figure's title: what was run, on which board, for whom, when ("Energy loss per
// flexion: amplitude protocol, node 2, subject S07, 2026-11-24T10:31:05Z").
std::string RunTitle(const RunRecord& record);

// Now as ISO 8601 UTC to the second ("2026-11-24T10:31:05Z").
std::string UtcNow();
// This machine's name ("unknown" when it has none).
std::string HostName();

// Where a run writes: `requested` when given — refused when it is a file, or a folder
// that is not empty unless `force` (then the files named in `outputs` are removed from
// it first, so no earlier run's file is left to be taken for this one's) — else a new
// folder `base`/<UTC time>/ ("out/trial/2026-11-24T10-31-05Z", with -2, -3… when the
// second is taken). Created. Throws std::runtime_error with the reason.
struct OutputFolder {
  std::filesystem::path path;
  bool chosen = false;  // true: the default, a new timestamped folder
};
OutputFolder PrepareOutputFolder(const std::string& requested, const std::string& base,
                                 bool force, const std::vector<std::string>& outputs);

}  // namespace mjc::host
