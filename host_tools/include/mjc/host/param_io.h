// The board's parameters on the host (mjc param): the protocol's list
// (protocol/params.h) by key, values in the list's units converted exactly from and to
// the raw fixed-point integers that travel, the checks of the list (access, range) run
// before anything is sent, the board's answers, and the file `mjc param dump` writes
// and `mjc param restore` reads.
//
// Exactness: a value is raw / 2^frac_bits with |raw| < 2^31, which a double holds
// exactly, and which has a finite decimal expansion of at most frac_bits digits after
// the point: FormatParamValue writes every one of them. A value asked for is rounded to
// the nearest raw step (half away from zero); when that changes it, the tools say what
// will be stored.
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "mjc/host/board_client.h"
#include "mjc/protocol/messages.h"

namespace mjc::host {

// The entry of the list named `key`; nullptr for a key no parameter has.
const protocol::ParamInfo* FindParam(std::string_view key);
// Every key of the list, in its order.
std::span<const std::string_view> ParamKeys();
// "unknown key 'posiion_kp' (did you mean 'position_kp'?)" (mjc/strict_json.h).
std::string UnknownParamMessage(std::string_view key);

// raw / 2^frac_bits, exactly.
double ParamValueOf(const protocol::ParamInfo& info, std::int32_t raw);
// The same as an exact decimal: "0.100006103515625", "1000", "-0.5".
std::string FormatParamValue(const protocol::ParamInfo& info, std::int32_t raw);
// "0.5 1/rad", "1000 Hz", "1" (no unit).
std::string FormatParamWithUnit(const protocol::ParamInfo& info, std::int32_t raw);
// The range a write may take, in the list's units: "0..10000 Hz".
std::string ParamRangeText(const protocol::ParamInfo& info);
// "control" (applied by the tick, only while idle), "node" (at once), "guard" (at once,
// only while no motion runs), "joint limit" (by the tick while idle, only tightened),
// "read-only".
std::string_view ParamAccessName(protocol::ParamAccess access);

// A write the list allows.
struct ParamSetting {
  const protocol::ParamInfo* info = nullptr;
  std::int32_t raw = 0;
  double given = 0;   // the value asked for, in the list's units
  bool exact = true;  // given == raw / 2^frac_bits
  // "position_kp: 0.1 will be stored as 0.100006103515625 (the nearest step of
  // 1/65536)";
  // empty when exact.
  std::string RoundingNote() const;
};

// `value` (in the list's units) for `info`, rounded to its format and checked against
// its access and range: nullopt with *why naming the key ("position_kp: -1 is outside
// 0..32767.9999847412109375 1/rad", "calibration_alpha is read-only: …") otherwise.
std::optional<ParamSetting> CheckParamWrite(const protocol::ParamInfo& info, double value,
                                            std::string* why);
// KEY=VALUE as the command line gives it (a decimal number; no hex, inf or nan),
// through CheckParamWrite. nullopt with *why.
std::optional<ParamSetting> ParseParamAssignment(std::string_view text, std::string* why);

// --- the board ---------------------------------------------------------------------

struct ParamReading {
  const protocol::ParamInfo* info = nullptr;
  std::int32_t raw = 0;
};

// Reads `which` from the board, in that order (each waiting timeout_ms of the board's
// time, as BoardClient::ReadParam). nullopt with the first failure's reason.
std::optional<std::vector<ParamReading>> ReadParams(
    BoardClient& board, std::span<const protocol::ParamInfo* const> which, int timeout_ms,
    std::string* why);
// Every parameter of the list, in its order.
std::vector<const protocol::ParamInfo*> AllParams();

// Whether the board speaks this tool's protocol (protocol::kVersion), read from its
// protocol_version.
enum class ProtocolCheck : std::uint8_t {
  kSame = 0,
  kOther = 1,     // *why names both versions
  kNoAnswer = 2,  // the read was not answered (an image from before protocol versions
                  // never answers it: its decoder refuses the id); board.link_failed()
                  // and board.ambiguous() tell the causes apart as for any read
};
ProtocolCheck CheckProtocolVersion(BoardClient& board, int timeout_ms, std::string* why);

// How a series of writes ended.
enum class ParamWriteEnd : std::uint8_t {
  kDone = 0,      // every setting written and read back
  kNoAnswer = 1,  // a write or read was not answered (or could not be sent)
  kRefused = 2,   // the board refused a write (status says why)
  kNotKept = 3,   // a write was accepted but the value read back differs
  kNotIdle = 4,   // (restore) the board runs a motion or holds a fault: nothing sent
};

struct ParamWriteOutcome {
  ParamWriteEnd end = ParamWriteEnd::kDone;
  std::size_t written = 0;    // settings the board took, each read back as sent
  std::size_t unchanged = 0;  // (restore) settings the board already held: not sent
  protocol::ParamStatus status = protocol::ParamStatus::kOk;  // with kRefused
  std::string why;  // with every end but kDone, naming the parameter
};

// Writes each setting in order, each answered by the board and read back; stops at the
// first that is not.
ParamWriteOutcome WriteParams(BoardClient& board, std::span<const ParamSetting> settings,
                              int timeout_ms);

// A restore: the board's state first — while it runs a trial or a calibration sweep,
// or holds a fault, it refuses control parameters and protections (those of
// protocol::RefusedWhileMoving), so a restore that has any is
// refused whole (kNotIdle) before anything is sent. Then the settings' present values
// are read, those the board does not already hold are written (WriteParams), and every
// setting is read back at the end.
ParamWriteOutcome RestoreParams(BoardClient& board,
                                std::span<const ParamSetting> settings, int timeout_ms);

// --- the dump file -----------------------------------------------------------------

// The keys of a dump's top level.
inline constexpr std::string_view kParamFileKeys[] = {
    "protocol_version", "node", "build", "instance", "dumped_utc", "params", "read_only"};

// A dump: this protocol's version, the node and its board (BoardInfo: build,
// instance; null without one), when, and every reading — writable parameters under
// "params" (what a restore writes), read-only ones under "read_only" (what the board
// held, for the record).
// Ordered as the list, so the file reads in the list's order.
nlohmann::ordered_json ParamDumpToJson(int node,
                                       const std::optional<protocol::BoardInfo>& info,
                                       std::span<const ParamReading> readings,
                                       const std::string& dumped_utc);

// A restore file checked whole, before anything is sent: the writes it asks for, in
// the list's order. nullopt with *why when it is not a dump's shape (an unknown key is
// named with the nearest known one), its protocol_version is not this tool's, a key
// under "params" is unknown or read-only, a key under "read_only" is unknown or
// writable, or a value is not a finite number or out of its range. "params" is
// required; the keys it leaves out are left as the board has them. A value that does
// not round-trip is kept, rounded (ParamSetting::RoundingNote).
std::optional<std::vector<ParamSetting>> ParamRestoreFromJson(const nlohmann::json& file,
                                                              std::string* why);

}  // namespace mjc::host
