#include "mjc/host/run_record.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <ctime>
#include <fstream>
#include <iterator>
#include <stdexcept>

#include "mjc/host/describe.h"
#include "mjc/host/mat_record.h"
#include "mjc/host/param_io.h"
#include "mjc/host/report.h"
#include "mjc/host/robot_description.h"
#include "mjc/host/units.h"
#include "mjc/strict_json.h"

namespace mjc::host {
namespace {

// Version 2 added the run's pid, the board's parameters, the robot description's
// content and the cable friction in force; version 1 files are read too.
constexpr std::string_view kFormat = "mjc run 2";
constexpr std::string_view kFormatV1 = "mjc run 1";
constexpr std::string_view kKeysV1[] = {
    "format",       "command",     "node",    "iface",       "board",
    "calibration",  "robot",       "subject", "protocol",    "amplitudes_deg",
    "frequency_hz", "repetitions", "rest_s",  "started_utc", "host",
    "mjc",          "end"};
constexpr std::string_view kKeys[] = {
    "format",       "command",     "node",    "iface",       "board",
    "calibration",  "robot",       "subject", "protocol",    "amplitudes_deg",
    "frequency_hz", "repetitions", "rest_s",  "started_utc", "host",
    "mjc",          "end",         "pid",     "params"};
constexpr std::string_view kCommands[] = {"trial", "calibrate"};
constexpr std::string_view kProtocols[] = {"repeatability", "amplitude",
                                           "calibration sweep"};
constexpr std::string_view kRobotKeys[] = {"path", "description"};
constexpr std::string_view kBoardKeys[] = {"build", "dirty", "image", "reset_cause",
                                           "instance"};
constexpr std::string_view kHeldKeysV1[] = {
    "calibrated",      "c_right_deg", "c_left_deg", "alpha", "sea_stiffness_Nm_per_rad",
    "joint_zero_count"};
constexpr std::string_view kHeldKeys[] = {"calibrated",
                                          "c_right_deg",
                                          "c_left_deg",
                                          "alpha",
                                          "sea_stiffness_Nm_per_rad",
                                          "joint_zero_count",
                                          "cable_friction_Nm"};

std::string Hex(std::uint32_t v, int digits) {
  char out[16];
  std::snprintf(out, sizeof out, "%0*x", digits, v);
  return out;
}

using Reader = strict::FieldReader<nlohmann::json>;

// One of `known`, or a failure naming them.
std::string OneOf(const Reader& in, const nlohmann::json& object, std::string_view prefix,
                  std::string_view key, std::span<const std::string_view> known) {
  const std::string text = in.String(object, prefix, key);
  if (std::find(known.begin(), known.end(), text) != known.end()) return text;
  std::string names;
  for (const std::string_view k : known) {
    names += (names.empty() ? "" : ", ") + std::string("\"") + std::string(k) + "\"";
  }
  in.Fail(
      strict::FieldName(prefix, key),
      "\"" + text + "\" is none of " + names +
          (strict::Closest(text, known)
               ? " (did you mean \"" + std::string(*strict::Closest(text, known)) + "\"?)"
               : ""));
}

// A finite number within [lo, hi] (`unit` after the range in the message).
double NumberIn(const Reader& in, const nlohmann::json& object, std::string_view prefix,
                std::string_view key, double lo, double hi, const std::string& unit) {
  const double v = in.Double(object, prefix, key);
  if (!std::isfinite(v) || v < lo || v > hi) {
    char text[96];
    std::snprintf(text, sizeof text, "= %g is outside [%g, %g]%s", v, lo, hi,
                  unit.c_str());
    in.Fail(strict::FieldName(prefix, key), text);
  }
  return v;
}
constexpr std::string_view kEndKeys[] = {"outcome", "fault", "message"};
constexpr std::string_view kFaultKeys[] = {"code", "name"};

// A number written as `digits` lower-case hex digits ("board.build").
std::uint32_t HexNumber(const Reader& in, const nlohmann::json& object,
                        std::string_view prefix, std::string_view key,
                        std::size_t digits) {
  const std::string text = in.String(object, prefix, key);
  const bool ok =
      text.size() == digits && std::all_of(text.begin(), text.end(), [](char c) {
        return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f');
      });
  if (!ok) {
    in.Fail(strict::FieldName(prefix, key),
            "must be " + std::to_string(digits) + " lower-case hex digits");
  }
  return static_cast<std::uint32_t>(std::stoul(text, nullptr, 16));
}

// An integer within [lo, hi]; a value that is no integer is told the range too.
std::int64_t IntegerIn(const Reader& in, const nlohmann::json& object,
                       std::string_view prefix, std::string_view key, std::int64_t lo,
                       std::int64_t hi) {
  if (!in.Value(object, prefix, key).is_number_integer()) {
    in.Fail(
        strict::FieldName(prefix, key),
        "must be an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
  }
  return in.Integer(object, prefix, key, lo, hi);
}

// The object `key` of `object`, every key of it in `known`; null when the run had none
// (an older image sends no BoardInfo; a run that did not fault has no fault).
const nlohmann::json* OptionalSection(const Reader& in, const nlohmann::json& object,
                                      std::string_view prefix, std::string_view key,
                                      std::span<const std::string_view> known) {
  const nlohmann::json& v = in.Value(object, prefix, key);
  if (v.is_null()) return nullptr;
  const std::string name = strict::FieldName(prefix, key);
  if (!v.is_object()) in.Fail(name, "must be null or an object");
  in.CheckKnown(v, name + ".", known);
  return &v;
}

}  // namespace

nlohmann::json RunRecordToJson(const RunRecord& r) {
  nlohmann::json j;
  j["format"] = kFormat;
  j["command"] = r.command;
  j["node"] = r.node;
  j["iface"] = r.iface;
  if (r.board) {
    j["board"] = {{"build", Hex(r.board->build, 8)},
                  {"dirty", r.board->dirty},
                  {"image", ImageName(r.board->image)},
                  {"reset_cause", ResetCauseName(r.board->reset_cause)},
                  {"instance", Hex(r.board->instance, 4)}};
  } else {
    j["board"] = nullptr;
  }
  if (r.calibration) {
    const auto& c = r.calibration->record;
    j["calibration"] = {{"calibrated", r.calibration->calibrated},
                        {"c_right_deg", RadToDeg(c.backlash.c_right.ToDouble())},
                        {"c_left_deg", RadToDeg(c.backlash.c_left.ToDouble())},
                        {"alpha", c.backlash.alpha.ToDouble()},
                        {"sea_stiffness_Nm_per_rad", c.sea_stiffness.ToDouble()},
                        {"joint_zero_count", c.joint_zero_count},
                        {"cable_friction_Nm", c.backlash.cable_friction.ToDouble()}};
  } else {
    j["calibration"] = nullptr;
  }
  j["robot"] = r.robot;
  j["subject"] = r.subject ? nlohmann::json(*r.subject) : nlohmann::json(nullptr);
  j["protocol"] = r.protocol;
  j["amplitudes_deg"] = r.amplitudes_deg;
  j["frequency_hz"] = r.frequency_hz;
  j["repetitions"] = r.repetitions;
  j["rest_s"] = r.rest_s;
  j["started_utc"] = r.started_utc;
  j["host"] = r.host;
  j["mjc"] = r.mjc;
  nlohmann::json fault = nullptr;
  if (r.end.fault_code) {
    fault = {{"code", *r.end.fault_code},
             {"name", FaultName(static_cast<Fault>(*r.end.fault_code))}};
  }
  j["end"] = {{"outcome", r.end.outcome}, {"fault", fault}, {"message", r.end.message}};
  j["pid"] = r.pid ? nlohmann::json(*r.pid) : nlohmann::json(nullptr);
  j["params"] = r.params;
  return j;
}

std::optional<RunRecord> RunRecordFromJson(const nlohmann::json& j, std::string* why) {
  RunRecord r;
  // Each failure a std::runtime_error "run.json: field '<name>' <what>" (or an unknown
  // key, named with the known one it resembles).
  const Reader in("run.json");
  try {
    if (!j.is_object()) {
      throw std::runtime_error("run.json: the top level must be an object");
    }
    const std::string format = in.String(j, "", "format");
    if (format != kFormat && format != kFormatV1) {
      in.Fail("format", "is not \"" + std::string(kFormat) +
                            "\" (written by another version of mjc?)");
    }
    const bool v1 = format == kFormatV1;
    in.CheckKnown(j, "", v1 ? std::span<const std::string_view>(kKeysV1) : kKeys);
    r.command = OneOf(in, j, "", "command", kCommands);
    r.node = static_cast<int>(IntegerIn(in, j, "", "node", 1, 8));
    r.iface = in.String(j, "", "iface");
    if (const auto* b = OptionalSection(in, j, "", "board", kBoardKeys)) {
      protocol::BoardInfo info;
      info.build = HexNumber(in, *b, "board", "build", 8);
      info.dirty = in.Bool(*b, "board", "dirty");
      const std::string image = in.String(*b, "board", "image");
      if (image != "application" && image != "bootloader") {
        in.Fail("board.image", "must be \"application\" or \"bootloader\"");
      }
      info.image = image == "bootloader" ? protocol::ImageKind::kBootloader
                                         : protocol::ImageKind::kApplication;
      const std::string cause = in.String(*b, "board", "reset_cause");
      bool known = false;
      for (int c = 0; c <= 5; ++c) {
        if (ResetCauseName(static_cast<protocol::ResetCause>(c)) == cause) {
          info.reset_cause = static_cast<protocol::ResetCause>(c);
          known = true;
        }
      }
      if (!known) in.Fail("board.reset_cause", "\"" + cause + "\" is unknown");
      info.instance =
          static_cast<std::uint16_t>(HexNumber(in, *b, "board", "instance", 4));
      r.board = info;
    }
    if (const auto* c = OptionalSection(
            in, j, "", "calibration",
            v1 ? std::span<const std::string_view>(kHeldKeysV1) : kHeldKeys)) {
      BoardCalibration held;
      held.calibrated = in.Bool(*c, "calibration", "calibrated");
      held.record.backlash.c_right = Angle::Quantize(
          DegToRad(NumberIn(in, *c, "calibration", "c_right_deg", -28.65, 28.65, "°")));
      held.record.backlash.c_left = Angle::Quantize(
          DegToRad(NumberIn(in, *c, "calibration", "c_left_deg", -28.65, 28.65, "°")));
      held.record.backlash.alpha =
          Scale::Quantize(NumberIn(in, *c, "calibration", "alpha", 0, 8, ""));
      held.record.sea_stiffness = Stiffness::Quantize(NumberIn(
          in, *c, "calibration", "sea_stiffness_Nm_per_rad", 0, 100, " N·m/rad"));
      held.record.joint_zero_count = static_cast<std::uint16_t>(
          IntegerIn(in, *c, "calibration", "joint_zero_count", 0, 16383));
      if (!v1) {
        held.record.backlash.cable_friction = Torque::Quantize(
            NumberIn(in, *c, "calibration", "cable_friction_Nm", 0, 5, " N·m"));
      }
      r.calibration = held;
    }
    r.robot = in.Value(j, "", "robot");
    if (!r.robot.is_null() && !r.robot.is_object()) {
      in.Fail("robot", "must be null or an object");
    }
    if (!v1 && r.robot.is_object()) {
      in.CheckKnown(r.robot, "robot.", kRobotKeys);
      const std::string path = in.String(r.robot, "robot", "path");
      const auto& description = in.Value(r.robot, "robot", "description");
      if (!description.is_object()) in.Fail("robot.description", "must be an object");
      std::string refused;
      if (!ParseRobotDescription(description.dump(), "robot.description", &refused)) {
        throw std::runtime_error("run.json: " + refused);
      }
    }
    if (!in.Value(j, "", "subject").is_null()) r.subject = in.String(j, "", "subject");
    r.protocol = OneOf(in, j, "", "protocol", kProtocols);
    if ((r.command == "calibrate") != (r.protocol == "calibration sweep")) {
      in.Fail("protocol", "\"" + r.protocol + "\" is not a protocol of mjc " + r.command);
    }
    const auto& amplitudes = in.Value(j, "", "amplitudes_deg");
    if (!amplitudes.is_array()) in.Fail("amplitudes_deg", "must be an array");
    for (std::size_t i = 0; i < amplitudes.size(); ++i) {
      const std::string name = "amplitudes_deg[" + std::to_string(i) + "]";
      if (!amplitudes[i].is_number()) in.Fail(name, "must be a number");
      const double a = amplitudes[i].get<double>();
      if (!std::isfinite(a) || a < 1 || a > 90) {
        in.Fail(name, "= " + amplitudes[i].dump() + " is outside [1, 90]°");
      }
      r.amplitudes_deg.push_back(a);
    }
    if (r.amplitudes_deg.empty()) in.Fail("amplitudes_deg", "is empty");
    r.frequency_hz = NumberIn(in, j, "", "frequency_hz", 0.08, 5, " Hz");
    r.repetitions = static_cast<int>(IntegerIn(in, j, "", "repetitions", 1, 255));
    r.rest_s = NumberIn(in, j, "", "rest_s", 0, 25.5, " s");
    r.started_utc = in.String(j, "", "started_utc");
    r.host = in.String(j, "", "host");
    r.mjc = in.String(j, "", "mjc");
    const auto& end = in.Section(j, "end", kEndKeys);
    r.end.outcome = in.String(end, "end", "outcome");
    if (std::find(std::begin(kRunOutcomes), std::end(kRunOutcomes), r.end.outcome) ==
        std::end(kRunOutcomes)) {
      in.Fail("end.outcome", "\"" + r.end.outcome + "\" is unknown");
    }
    if (const auto* f = OptionalSection(in, end, "end", "fault", kFaultKeys)) {
      r.end.fault_code =
          static_cast<int>(IntegerIn(in, *f, "end.fault", "code", 0, 65535));
      (void)in.String(*f, "end.fault", "name");
    }
    r.end.message = in.String(end, "end", "message");
    if (r.end.fault_code.has_value() != (r.end.outcome == "faulted")) {
      in.Fail("end.fault", r.end.fault_code
                               ? "is given, but the outcome is not \"faulted\""
                               : "is null, but the outcome is \"faulted\"");
    }
    if (!v1) {
      if (!in.Value(j, "", "pid").is_null()) {
        r.pid = static_cast<long>(IntegerIn(in, j, "", "pid", 1, 4194304));
      }
      r.params = in.Value(j, "", "params");
      if (!r.params.is_null()) {
        if (!r.params.is_object()) in.Fail("params", "must be null or an object");
        for (const auto& [key, value] : r.params.items()) {
          const protocol::ParamInfo* info = FindParam(key);
          if (info == nullptr) {
            throw std::runtime_error("run.json: params: " + UnknownParamMessage(key));
          }
          const double lo = ParamValueOf(*info, static_cast<std::int32_t>(info->min_raw));
          const double hi = ParamValueOf(*info, static_cast<std::int32_t>(info->max_raw));
          (void)NumberIn(in, r.params, "params", key, lo, hi, "");
        }
      }
    }
  } catch (const std::exception& e) {
    *why = e.what();
    return std::nullopt;
  }
  return r;
}

void WriteRunRecord(const RunRecord& record, const std::filesystem::path& dir) {
  ReplaceFile(dir / "run.json", RunRecordToJson(record).dump(2) + "\n");
  // The run ended: its records, all in, also as one MATLAB file.
  if (record.end.outcome != "running") {
    std::string why;
    if (!WriteRunMat(dir, &why)) throw std::runtime_error(why);
  }
}

std::optional<RunRecord> ReadRunRecord(const std::filesystem::path& dir,
                                       std::string* why) {
  why->clear();
  const std::filesystem::path path = dir / "run.json";
  std::error_code error;
  if (!std::filesystem::exists(path, error)) return std::nullopt;
  nlohmann::json j;
  try {
    const auto text = ReadFileText(path);
    if (!text) throw std::runtime_error(path.string() + ": cannot read it");
    // Strict: a repeated key or anything after the object is refused, not ignored.
    j = strict::ParseObject<nlohmann::json>(*text, path.string());
  } catch (const std::exception& e) {
    *why = e.what();
    return std::nullopt;
  }
  auto record = RunRecordFromJson(j, why);
  if (!record) *why = dir.string() + "/" + *why;
  return record;
}

bool RunStillGoing(const RunRecord& record) {
  if (!record.pid || record.host != HostName()) return false;
  // /proc/<pid>/comm: the process's name, so a pid used again by another program does
  // not count.
  std::ifstream comm("/proc/" + std::to_string(*record.pid) + "/comm");
  std::string name;
  return std::getline(comm, name) && name == "mjc";
}

nlohmann::json RobotRecord(const std::string& path, const std::string& text) {
  return {{"path", path},
          {"description", strict::ParseObject<nlohmann::json>(text, path)}};
}

nlohmann::json ReadBoardParams(BoardClient& board, std::string* why) {
  const auto all = AllParams();
  const auto readings = ReadParams(board, all, 500, why);
  if (!readings) return nullptr;
  nlohmann::json out = nlohmann::json::object();
  for (const ParamReading& r : *readings) out[r.info->key] = ParamValueOf(*r.info, r.raw);
  return out;
}

void DiscardUnstartedRun(const std::filesystem::path& dir,
                         const std::vector<std::string>& outputs, bool created) {
  std::error_code ignored;
  for (const std::string& name : outputs) std::filesystem::remove(dir / name, ignored);
  std::filesystem::remove(dir / "run.json.tmp", ignored);
  if (created && std::filesystem::is_empty(dir, ignored)) {
    std::filesystem::remove(dir, ignored);
  }
}

std::string RunTitle(const RunRecord& r) {
  return "Energy loss per flexion: " + r.protocol + " protocol, node " +
         std::to_string(r.node) + (r.subject ? ", subject " + *r.subject : "") + ", " +
         r.started_utc;
}

std::string UtcNow() {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&now, &tm);
  char text[32];
  std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return text;
}

std::string HostName() {
  char name[256] = {};
  if (::gethostname(name, sizeof name - 1) != 0 || name[0] == '\0') return "unknown";
  return name;
}

OutputFolder PrepareOutputFolder(const std::string& requested, const std::string& base,
                                 bool force, const std::vector<std::string>& outputs) {
  namespace fs = std::filesystem;
  OutputFolder out;
  std::error_code error;
  if (requested.empty()) {
    // The run's start, in UTC like run.json's, with '-' for ':' (a file name on any
    // system).
    std::string stamp = UtcNow();
    std::replace(stamp.begin(), stamp.end(), ':', '-');
    out.path = fs::path(base) / stamp;
    for (int n = 2; fs::exists(out.path, error); ++n) {
      out.path = fs::path(base) / (stamp + "-" + std::to_string(n));
    }
    out.chosen = true;
  } else {
    out.path = requested;
    if (fs::exists(out.path, error) && !fs::is_directory(out.path, error)) {
      throw std::runtime_error(requested +
                               " is a file, not a folder: a run never "
                               "overwrites one; choose another --out");
    }
    if (fs::is_directory(out.path, error) && !fs::is_empty(out.path, error)) {
      if (!force) {
        std::vector<std::string> names;
        for (const auto& entry : fs::directory_iterator(out.path, error)) {
          names.push_back(entry.path().filename().string());
        }
        std::sort(names.begin(), names.end());
        std::string held;
        for (std::size_t i = 0; i < names.size() && i < 3; ++i) {
          held += (i ? ", " : "") + names[i];
        }
        if (names.size() > 3) held += ", …";
        throw std::runtime_error(requested + " is not empty (" + held +
                                 "): a run never overwrites another; choose a new --out, "
                                 "or add --force to replace its files");
      }
      for (const std::string& name : outputs) fs::remove(out.path / name, error);
    }
  }
  fs::create_directories(out.path, error);
  if (error) {
    throw std::runtime_error("cannot create " + out.path.string() + ": " +
                             error.message());
  }
  return out;
}

}  // namespace mjc::host
