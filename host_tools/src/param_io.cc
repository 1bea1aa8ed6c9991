#include "mjc/host/param_io.h"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iterator>

#include "mjc/host/describe.h"
#include "mjc/strict_json.h"

namespace mjc::host {
namespace {

using protocol::kParams;
using protocol::ParamAccess;
using protocol::ParamInfo;

constexpr auto kKeys = [] {
  std::array<std::string_view, std::size(kParams)> keys{};
  for (std::size_t i = 0; i < keys.size(); ++i) keys[i] = kParams[i].key;
  return keys;
}();

// The shortest text that reads back as `v` ("0.1", "1e-07").
std::string Shortest(double v) {
  char text[32];
  const auto end = std::to_chars(text, text + sizeof text, v).ptr;
  return std::string(text, end);
}

// [+-]digits[.digits][(e|E)[+-]digits], with at least one digit before the exponent:
// what a person types as a number (strtod alone would also take hex, inf and nan).
bool IsDecimal(std::string_view t) {
  std::size_t i = 0, digits = 0;
  const auto digit = [&] { return i < t.size() && t[i] >= '0' && t[i] <= '9'; };
  if (i < t.size() && (t[i] == '+' || t[i] == '-')) ++i;
  for (; digit(); ++i) ++digits;
  if (i < t.size() && t[i] == '.') {
    for (++i; digit(); ++i) ++digits;
  }
  if (digits == 0) return false;
  if (i < t.size() && (t[i] == 'e' || t[i] == 'E')) {
    ++i;
    if (i < t.size() && (t[i] == '+' || t[i] == '-')) ++i;
    std::size_t exponent = 0;
    for (; digit(); ++i) ++exponent;
    if (exponent == 0) return false;
  }
  return i == t.size();
}

std::string Node(const BoardClient& board) {
  return "node " + std::to_string(board.node());
}

}  // namespace

const ParamInfo* FindParam(std::string_view key) {
  for (const ParamInfo& p : kParams) {
    if (key == p.key) return &p;
  }
  return nullptr;
}

std::span<const std::string_view> ParamKeys() { return kKeys; }

std::string UnknownParamMessage(std::string_view key) {
  return strict::UnknownKeyMessage(key, ParamKeys());
}

double ParamValueOf(const ParamInfo& info, std::int32_t raw) {
  return std::ldexp(static_cast<double>(raw), -info.frac_bits);
}

std::string FormatParamValue(const ParamInfo& info, std::int32_t raw) {
  // |raw| = whole·2^f + rest; each decimal digit of rest / 2^f is the integer part of
  // ten times what is left, exactly, and the digits end within f of them (2^-f has f).
  const int f = info.frac_bits;
  const std::uint64_t mask = (std::uint64_t{1} << f) - 1;
  const std::uint64_t magnitude =
      raw < 0 ? std::uint64_t{0} - static_cast<std::uint64_t>(std::int64_t{raw})
              : static_cast<std::uint64_t>(raw);
  std::string out = (raw < 0 ? "-" : "") + std::to_string(magnitude >> f);
  std::uint64_t rest = magnitude & mask;
  if (rest != 0) out += '.';
  while (rest != 0) {
    rest *= 10;  // < 10·2^31
    out += static_cast<char>('0' + (rest >> f));
    rest &= mask;
  }
  return out;
}

std::string FormatParamWithUnit(const ParamInfo& info, std::int32_t raw) {
  const std::string unit = info.unit;
  return FormatParamValue(info, raw) + (unit.empty() ? "" : " " + unit);
}

std::string ParamRangeText(const ParamInfo& info) {
  const std::string unit = info.unit;
  return FormatParamValue(info, static_cast<std::int32_t>(info.min_raw)) + ".." +
         FormatParamValue(info, static_cast<std::int32_t>(info.max_raw)) +
         (unit.empty() ? "" : " " + unit);
}

std::string_view ParamAccessName(ParamAccess access) {
  switch (access) {
    case ParamAccess::kNode:
      return "node";
    case ParamAccess::kControl:
      return "control";
    case ParamAccess::kGuard:
      return "guard";
    case ParamAccess::kJointLimit:
      return "joint limit";
    case ParamAccess::kReadOnly:
      break;
  }
  return "read-only";
}

std::string ParamSetting::RoundingNote() const {
  if (exact) return "";
  const std::string steps = info->frac_bits == 0
                                ? "it takes whole numbers"
                                : "the nearest step of 1/" +
                                      std::to_string(std::uint64_t{1} << info->frac_bits);
  return std::string(info->key) + ": " + Shortest(given) + " will be stored as " +
         FormatParamValue(*info, raw) + " (" + steps + ")";
}

std::optional<ParamSetting> CheckParamWrite(const ParamInfo& info, double value,
                                            std::string* why) {
  const std::string key = info.key;
  if (info.access == ParamAccess::kReadOnly) {
    *why = key + " is read-only: the board reports it and takes no writes (" + info.what +
           "; a calibration is uploaded whole, with mjc cal upload)";
    return std::nullopt;
  }
  if (!std::isfinite(value)) {
    *why = key + ": not a finite number";
    return std::nullopt;
  }
  // Exact: a power of two; the bound keeps llround's argument within a long long.
  const double scaled = std::ldexp(value, info.frac_bits);
  const long long raw = std::fabs(scaled) < 0x1p62 ? std::llround(scaled) : 0;
  if (std::fabs(scaled) >= 0x1p62 || raw < info.min_raw || raw > info.max_raw) {
    *why = key + ": " + Shortest(value) + " is outside " + ParamRangeText(info);
    return std::nullopt;
  }
  ParamSetting s;
  s.info = &info;
  s.raw = static_cast<std::int32_t>(raw);
  s.given = value;
  s.exact = ParamValueOf(info, s.raw) == value;
  return s;
}

std::optional<ParamSetting> ParseParamAssignment(std::string_view text,
                                                 std::string* why) {
  const std::size_t equals = text.find('=');
  if (equals == std::string_view::npos) {
    *why = "'" + std::string(text) + "': expected KEY=VALUE";
    return std::nullopt;
  }
  const std::string_view key = text.substr(0, equals);
  const std::string value(text.substr(equals + 1));
  const ParamInfo* info = FindParam(key);
  if (info == nullptr) {
    *why = UnknownParamMessage(key);
    return std::nullopt;
  }
  if (!IsDecimal(value)) {
    *why = std::string(key) + ": '" + value + "' is not a decimal number";
    return std::nullopt;
  }
  return CheckParamWrite(*info, std::strtod(value.c_str(), nullptr), why);
}

std::vector<const ParamInfo*> AllParams() {
  std::vector<const ParamInfo*> out;
  for (const ParamInfo& p : kParams) out.push_back(&p);
  return out;
}

std::optional<std::vector<ParamReading>> ReadParams(
    BoardClient& board, std::span<const ParamInfo* const> which, int timeout_ms,
    std::string* why) {
  std::vector<ParamReading> out;
  for (const ParamInfo* info : which) {
    const auto raw = board.ReadParam(info->id, timeout_ms, why);
    if (!raw) {
      *why = "reading " + std::string(info->key) + ": " + *why;
      return std::nullopt;
    }
    out.push_back({info, *raw});
  }
  return out;
}

ProtocolCheck CheckProtocolVersion(BoardClient& board, int timeout_ms, std::string* why) {
  const std::uint64_t frames_before = board.frames();
  const auto version =
      board.ReadParam(protocol::ParamId::kProtocolVersion, timeout_ms, why);
  if (!version) {
    // It talked all along but left the read unanswered: a decoder that does not know
    // the id.
    if (!board.link_failed() && !board.ambiguous() && board.frames() > frames_before) {
      *why +=
          " (an image from before protocol versions does not know protocol_version; "
          "mjc list names its build)";
    }
    return ProtocolCheck::kNoAnswer;
  }
  if (*version != protocol::kVersion) {
    *why = Node(board) + " speaks protocol version " + std::to_string(*version) +
           ", this mjc " + std::to_string(protocol::kVersion) +
           ": its parameters may mean other things (use an mjc of the board's build: mjc "
           "list names it)";
    return ProtocolCheck::kOther;
  }
  return ProtocolCheck::kSame;
}

ParamWriteOutcome WriteParams(BoardClient& board, std::span<const ParamSetting> settings,
                              int timeout_ms) {
  ParamWriteOutcome out;
  const auto end = [&out](ParamWriteEnd e, std::string why) {
    out.end = e;
    out.why = std::move(why);
    return out;
  };
  for (const ParamSetting& s : settings) {
    const std::string key = s.info->key;
    const std::string value = key + " = " + FormatParamValue(*s.info, s.raw);
    std::string why;
    const auto answer = board.WriteParam(s.info->id, s.raw, timeout_ms, &why);
    if (!answer) return end(ParamWriteEnd::kNoAnswer, "writing " + key + ": " + why);
    if (answer->status != protocol::ParamStatus::kOk) {
      out.status = answer->status;
      std::string rule;
      switch (answer->status) {
        case protocol::ParamStatus::kOutOfRange:
          // Within the list's range, so the board's check of the whole configuration
          // refused it: the parameter's description names its rule.
          rule = std::string(" (") + s.info->what + ")";
          break;
        case protocol::ParamStatus::kBelowMinimum:
        case protocol::ParamStatus::kAboveMaximum:
        case protocol::ParamStatus::kBeyondJointLimit:
          // The board names the bound (its list may be another build's than ours).
          rule = ": " + FormatParamWithUnit(*s.info, answer->value);
          break;
        default:
          break;
      }
      return end(ParamWriteEnd::kRefused,
                 Node(board) + " refused " + value + ": " +
                     std::string(ParamStatusName(answer->status)) + rule);
    }
    const auto back = board.ReadParam(s.info->id, timeout_ms, &why);
    if (!back) return end(ParamWriteEnd::kNoAnswer, "reading " + key + " back: " + why);
    if (*back != s.raw) {
      return end(ParamWriteEnd::kNotKept, Node(board) + " holds " + key + " = " +
                                              FormatParamValue(*s.info, *back) +
                                              " after accepting " + value);
    }
    ++out.written;
  }
  return out;
}

ParamWriteOutcome RestoreParams(BoardClient& board,
                                std::span<const ParamSetting> settings, int timeout_ms) {
  ParamWriteOutcome out;
  const auto end = [&out](ParamWriteEnd e, std::string why) {
    out.end = e;
    out.why = std::move(why);
    return out;
  };
  const BoardStatus& status = board.status();
  const bool control = std::any_of(settings.begin(), settings.end(), [](const auto& s) {
    return protocol::RefusedWhileMoving(s.info->access);
  });
  if (control && !status.heard) {
    return end(ParamWriteEnd::kNoAnswer, "no heartbeat heard from " + Node(board) +
                                             ": its state is unknown; nothing was sent");
  }
  if (control && status.state != protocol::BoardState::kIdle) {
    const std::string doing =
        status.state == protocol::BoardState::kFault
            ? "holds fault " + DescribeFault(status.fault) + " (mjc clear --node " +
                  std::to_string(board.node()) + " once its cause is gone)"
            : "is " + std::string(StateName(status.state)) +
                  (status.state == protocol::BoardState::kRunning
                       ? " (a trial or a stream)"
                       : " (a calibration sweep)");
    return end(ParamWriteEnd::kNotIdle,
               Node(board) + " " + doing +
                   ": the board takes control parameters and protections only while "
                   "idle; nothing was sent");
  }
  std::vector<const ParamInfo*> which;
  for (const ParamSetting& s : settings) which.push_back(s.info);
  std::string why;
  const auto before = ReadParams(board, which, timeout_ms, &why);
  if (!before) return end(ParamWriteEnd::kNoAnswer, why + "; nothing was sent");
  std::vector<ParamSetting> changes;
  for (std::size_t i = 0; i < settings.size(); ++i) {
    if ((*before)[i].raw != settings[i].raw) changes.push_back(settings[i]);
  }
  const std::size_t unchanged = settings.size() - changes.size();
  out = WriteParams(board, changes, timeout_ms);
  out.unchanged = unchanged;
  if (out.end != ParamWriteEnd::kDone) return out;
  // The whole file against what the board holds now: what it already held included.
  const auto after = ReadParams(board, which, timeout_ms, &why);
  if (!after) return end(ParamWriteEnd::kNoAnswer, why);
  for (std::size_t i = 0; i < settings.size(); ++i) {
    const ParamSetting& s = settings[i];
    if ((*after)[i].raw != s.raw) {
      return end(ParamWriteEnd::kNotKept,
                 Node(board) + " holds " + s.info->key + " = " +
                     FormatParamValue(*s.info, (*after)[i].raw) + ", not " +
                     FormatParamValue(*s.info, s.raw) + " as restored");
    }
  }
  return out;
}

nlohmann::ordered_json ParamDumpToJson(int node,
                                       const std::optional<protocol::BoardInfo>& info,
                                       std::span<const ParamReading> readings,
                                       const std::string& dumped_utc) {
  nlohmann::ordered_json j;
  j["protocol_version"] = protocol::kVersion;
  j["node"] = node;
  if (info) {
    char hex[8];
    std::snprintf(hex, sizeof hex, "%04x", info->instance);
    j["build"] = BuildName(info->build, info->dirty);
    j["instance"] = hex;
  } else {
    j["build"] = nullptr;
    j["instance"] = nullptr;
  }
  j["dumped_utc"] = dumped_utc;
  nlohmann::ordered_json params = nlohmann::ordered_json::object();
  nlohmann::ordered_json read_only = nlohmann::ordered_json::object();
  for (const ParamReading& r : readings) {
    auto& section = r.info->access == ParamAccess::kReadOnly ? read_only : params;
    // Whole numbers as integers; others as the double that is exactly raw / 2^frac
    // (written in as few digits as read back to it).
    if (r.info->frac_bits == 0) {
      section[r.info->key] = r.raw;
    } else {
      section[r.info->key] = ParamValueOf(*r.info, r.raw);
    }
  }
  j["params"] = params;
  j["read_only"] = read_only;
  return j;
}

std::optional<std::vector<ParamSetting>> ParamRestoreFromJson(const nlohmann::json& file,
                                                              std::string* why) {
  const auto fail = [why](std::string what) {
    *why = std::move(what);
    return std::nullopt;
  };
  if (!file.is_object()) return fail("the top level must be an object");
  if (const auto unknown = strict::UnknownKey(file, kParamFileKeys))
    return fail(*unknown);
  const auto& version =
      file.contains("protocol_version") ? file["protocol_version"] : nlohmann::json();
  if (!version.is_number_integer()) {
    return fail(
        "'protocol_version' missing or not a whole number (mjc param dump writes "
        "it)");
  }
  if (version.get<std::int64_t>() != protocol::kVersion) {
    return fail("dumped under protocol version " + version.dump() +
                ", and this mjc speaks " + std::to_string(protocol::kVersion) +
                ": its parameters may mean other things (restore it with an mjc of that "
                "version)");
  }
  if (file.contains("node")) {
    const auto& n = file["node"];
    if (!n.is_number_integer() || n.get<std::int64_t>() < protocol::kMinNode ||
        n.get<std::int64_t>() > protocol::kMaxNode) {
      return fail("'node' must be a whole number in 1..8, not " + n.dump());
    }
  }
  for (const char* key : {"build", "instance", "dumped_utc"}) {
    if (file.contains(key) && !file[key].is_string() && !file[key].is_null()) {
      return fail(std::string("'") + key + "' must be a string or null");
    }
  }
  if (!file.contains("params") || !file["params"].is_object()) {
    return fail("'params' missing or not an object (the parameters to write, by key)");
  }
  std::vector<ParamSetting> out;
  for (const auto& item : file["params"].items()) {
    const ParamInfo* info = FindParam(item.key());
    if (info == nullptr) {
      return fail(strict::UnknownKeyMessage(item.key(), ParamKeys(), "params."));
    }
    if (!item.value().is_number()) {
      return fail("params." + item.key() + " must be a number, not " +
                  item.value().dump());
    }
    std::string refused;
    const auto setting = CheckParamWrite(*info, item.value().get<double>(), &refused);
    if (!setting) return fail("params." + refused);
    out.push_back(*setting);
  }
  if (file.contains("read_only")) {
    const auto& held = file["read_only"];
    if (!held.is_object()) return fail("'read_only' must be an object");
    for (const auto& item : held.items()) {
      const ParamInfo* info = FindParam(item.key());
      if (info == nullptr) {
        return fail(strict::UnknownKeyMessage(item.key(), ParamKeys(), "read_only."));
      }
      if (info->access != ParamAccess::kReadOnly) {
        return fail("read_only." + item.key() +
                    " is writable: its place is under params, or a restore leaves it "
                    "out");
      }
      if (!item.value().is_number()) {
        return fail("read_only." + item.key() + " must be a number, not " +
                    item.value().dump());
      }
    }
  }
  // In the list's order, whatever the file's.
  std::sort(out.begin(), out.end(),
            [](const ParamSetting& a, const ParamSetting& b) { return a.info < b.info; });
  return out;
}

}  // namespace mjc::host
