// The board's parameters: one list, from which come the ParamId enum (stable numbers on
// the wire), the decoder's check of an id, the DBC's names for the ids, the host's names
// and units, and the ranges the board checks before applying a write. The board binds
// each id to its field (firmware/app/src/param_access.cc, checked complete against this
// list at compile time).
//
// Values travel as raw integers: a fixed-point field's raw value (value = raw / 2^frac),
// an integer field as itself.
//
// The protocol's version (kVersion) says what the list and the messages mean. The board
// reports it as a parameter (protocol_version); the host tools refuse a board of
// another version, and `mjc param restore` a file dumped under another one.
#pragma once

#include <cstdint>
#include <limits>

#include "mjc/core/control_tick.h"
#include "mjc/core/quantities.h"

namespace mjc::protocol {

// The version of the messages and the parameter list: raised when a message's layout,
// or a parameter's id, key, unit, format or range, changes its meaning, so that a board,
// a tool and a parameter file of different versions refuse each other instead of
// misreading raw values. Adding a message or a parameter keeps it. The DBC's VERSION
// line carries it.
inline constexpr std::uint16_t kVersion = 1;

// The board's clock as the Heartbeat's `tick` counts it: control ticks at the board's
// 10 kHz (ControlConfig's default; the app checks the two agree). The host measures the
// board's own progress with it, so its waits follow a board that runs slower than real
// time (a simulated one on a loaded machine).
inline constexpr std::uint32_t kBoardTickHz = 10000;

// The board's transmit rates, Hz, 0 = off; each at most the tick rate (the kNode
// parameters telemetry_*_hz, heartbeat_hz set them). Defaults: the angles at 1 kHz, the
// rest at 10 Hz, the board's identity (BoardInfo) also at 10 Hz — so a tool learns within
// 100 ms of a board's time whether two boards answer with one node id, before it acts;
// the bus load of eight boards is
// `./bench`'s busload_8x1khz_fd_pct (mjc busload). The energy figures need no more: the
// board integrates every tick and reports exact window totals.
struct TelemetryRates {
  std::uint16_t angles_hz = 1000;
  std::uint16_t torque_hz = 10;
  std::uint16_t power_hz = 10;
  std::uint16_t energy_hz = 10;
  std::uint16_t control_hz = 10;
  std::uint16_t heartbeat_hz = 10;
  std::uint16_t info_hz = 10;  // BoardInfo
};

// Who applies a write.
enum class ParamAccess : std::uint8_t {
  kNode = 0,      // the CAN node's own setting: applied at once
  kControl = 1,   // the control configuration: applied by the tick, only while idle;
                  // the tick then judges the whole configuration (ControlTick::Validate)
  kReadOnly = 2,  // what the board holds: the calibration (uploaded whole over ISO-TP),
                  // the running image
};

namespace param_detail {
inline constexpr std::int64_t kI32Max = std::numeric_limits<std::int32_t>::max();
inline constexpr std::int64_t kI32Min = std::numeric_limits<std::int32_t>::min();
}  // namespace param_detail

// X(Name, id, key, unit, frac_bits, min_raw, max_raw, access, what)
// min/max bound the raw value of a write (inclusive); a read-only one's bounds are what
// the board may report.
#define MJC_PARAM_LIST(X)                                                                \
  X(kTelemetryAnglesHz, 0x0100, "telemetry_angles_hz", "Hz", 0, 0, kBoardTickHz, kNode,  \
    "rate of the angle samples (one a TelemetryAngles; CAN FD: five a batch; 0: off)")   \
  X(kTelemetryTorqueHz, 0x0101, "telemetry_torque_hz", "Hz", 0, 0, kBoardTickHz, kNode,  \
    "rate of TelemetryTorque (0: off)")                                                  \
  X(kTelemetryPowerHz, 0x0102, "telemetry_power_hz", "Hz", 0, 0, kBoardTickHz, kNode,    \
    "rate of TelemetryPower (0: off)")                                                   \
  X(kTelemetryEnergyHz, 0x0103, "telemetry_energy_hz", "Hz", 0, 0, kBoardTickHz, kNode,  \
    "rate of TelemetryEnergy (0: off)")                                                  \
  X(kTelemetryControlHz, 0x0104, "telemetry_control_hz", "Hz", 0, 0, kBoardTickHz,       \
    kNode, "rate of TelemetryControl (0: off)")                                          \
  X(kHeartbeatHz, 0x0105, "heartbeat_hz", "Hz", 0, 0, kBoardTickHz, kNode,               \
    "rate of the Heartbeat (0: off; the tools need it)")                                 \
  X(kStreamTimeoutMs, 0x0110, "stream_timeout_ms", "ms", 0, 1, 60000, kNode,             \
    "streamed setpoints older than this stop the motor (fault 301)")                     \
  X(kHostTimeoutMs, 0x0111, "host_timeout_ms", "ms", 0, 0, 60000, kNode,                 \
    "a motion whose host session is silent this long stops (fault 302; 0: off)")         \
  X(kPositionKp, 0x0200, "position_kp", "1/rad", 16, 0, param_detail::kI32Max, kControl, \
    "position loop: duty per rad of error")                                              \
  X(kPositionKi, 0x0201, "position_ki", "1/(rad.s)", 16, 0, param_detail::kI32Max,       \
    kControl, "position loop: duty per rad.s of integrated error")                       \
  X(kPositionKd, 0x0202, "position_kd", "s/rad", 16, 0, param_detail::kI32Max, kControl, \
    "position loop: duty per rad/s of motor velocity")                                   \
  X(kPositionKff, 0x0203, "position_kff", "s/rad", 16, 0, param_detail::kI32Max,         \
    kControl, "position loop: duty per rad/s of setpoint velocity")                      \
  X(kVelocityWindow, 0x0210, "velocity_window", "ticks", 0,                              \
    VelocityEstimator::kMinWindow, ControlTick::kMaxVelocityWindow, kControl,            \
    "joint velocity estimator's window (odd; its delay aligns the torque)")              \
  X(kAttachmentPriorStiffness, 0x0211, "attachment_prior_stiffness", "N.m/rad",          \
    Stiffness::kFracBits, 0, param_detail::kI32Max, kControl,                            \
    "attachment k the velocity model assumes until a trial's window is fitted")          \
  X(kAttachmentPriorDamping, 0x0212, "attachment_prior_damping", "N.m.s/rad",            \
    Damping::kFracBits, 0, param_detail::kI32Max, kControl,                              \
    "attachment b the velocity model assumes until a trial's window is fitted")          \
  X(kTorqueMax, 0x0300, "torque_max", "N.m", Torque::kFracBits, 1,                       \
    param_detail::kI32Max, kControl, "SEA torque limit (fault 202 beyond it)")           \
  X(kCalibrationRight, 0x0400, "calibration_c_right", "rad", Angle::kFracBits,           \
    param_detail::kI32Min, param_detail::kI32Max, kReadOnly, "backlash offset c_r")      \
  X(kCalibrationLeft, 0x0401, "calibration_c_left", "rad", Angle::kFracBits,             \
    param_detail::kI32Min, param_detail::kI32Max, kReadOnly, "backlash offset c_l")      \
  X(kCalibrationAlpha, 0x0402, "calibration_alpha", "", Scale::kFracBits,                \
    param_detail::kI32Min, param_detail::kI32Max, kReadOnly, "pulley ratio r_m/r_j")     \
  X(kCalibrationStiffness, 0x0403, "calibration_stiffness", "N.m/rad",                   \
    Stiffness::kFracBits, param_detail::kI32Min, param_detail::kI32Max, kReadOnly,       \
    "SEA stiffness 2kr_j^2")                                                             \
  X(kCalibrationJointZero, 0x0404, "calibration_joint_zero", "counts", 0, 0, 16383,      \
    kReadOnly, "joint encoder count at zero")                                            \
  X(kCalibrated, 0x0405, "calibrated", "", 0, 0, 1, kReadOnly,                           \
    "1 once a calibration was accepted")                                                 \
  X(kCalibrationFriction, 0x0406, "calibration_cable_friction", "N.m",                   \
    Torque::kFracBits, 0, kMaxCableFriction.raw(), kReadOnly,                            \
    "sheath friction at the joint (0: not modelled)")                                    \
  X(kBuildId, 0x0500, "build_id", "", 0, param_detail::kI32Min, param_detail::kI32Max,   \
    kReadOnly, "the running image's commit (BoardInfo::build, as a signed value)")       \
  X(kProtocolVersion, 0x0501, "protocol_version", "", 0, 1, 0xFFFF, kReadOnly,           \
    "the protocol the running image speaks (kVersion)")

// Parameters readable and writable over the bus. Stable numbers: never renumbered.
enum class ParamId : std::uint16_t {
#define MJC_PARAM_ENUM(name, id, ...) name = id,
  MJC_PARAM_LIST(MJC_PARAM_ENUM)
#undef MJC_PARAM_ENUM
};

struct ParamInfo {
  ParamId id;
  const char* key;   // the host's name (mjc param), snake_case
  const char* unit;  // of value = raw / 2^frac_bits
  int frac_bits;
  std::int64_t min_raw;
  std::int64_t max_raw;
  ParamAccess access;
  const char* what;
};

inline constexpr ParamInfo kParams[] = {
#define MJC_PARAM_INFO(name, id, key, unit, frac, lo, hi, access, what) \
  {ParamId::name, key, unit, frac, lo, hi, ParamAccess::access, what},
    MJC_PARAM_LIST(MJC_PARAM_INFO)
#undef MJC_PARAM_INFO
};

// The entry of `id`; nullptr for a number no parameter has.
constexpr const ParamInfo* FindParam(ParamId id) {
  for (const ParamInfo& p : kParams) {
    if (p.id == id) return &p;
  }
  return nullptr;
}

// What the decoder accepts on the wire.
constexpr bool ValidEnumValue(ParamId id) { return FindParam(id) != nullptr; }

// A digest of what the list means (ids, keys, units, formats, ranges, access; not the
// descriptions): FNV-1a over each entry's fields.
consteval std::uint32_t ParamListDigest() {
  std::uint32_t h = 2166136261u;
  const auto byte = [&h](std::uint8_t b) { h = (h ^ b) * 16777619u; };
  const auto integer = [&byte](std::int64_t v) {
    for (int i = 0; i < 8; ++i)
      byte(static_cast<std::uint8_t>(static_cast<std::uint64_t>(v) >> (8 * i)));
  };
  const auto text = [&byte](const char* s) {
    for (; *s != '\0'; ++s) byte(static_cast<std::uint8_t>(*s));
    byte(0);
  };
  for (const ParamInfo& p : kParams) {
    integer(static_cast<std::uint16_t>(p.id));
    text(p.key);
    text(p.unit);
    integer(p.frac_bits);
    integer(p.min_raw);
    integer(p.max_raw);
    integer(static_cast<std::uint8_t>(p.access));
  }
  return h;
}
// The list as kVersion knows it. A change to the list fails here: when it changes what
// an existing parameter means (its id, key, unit, format or range), raise kVersion;
// then write the new digest here (the compiler's message names it: "ParamListIs()
// [with ... kDigest = N]").
inline constexpr std::uint32_t kParamListDigest = 493797895;
template <std::uint32_t kDigest>
constexpr bool ParamListIs() {
  static_assert(kDigest == kParamListDigest,
                "protocol/params.h: the parameter list changed; see kParamListDigest");
  return true;
}
static_assert(ParamListIs<ParamListDigest()>());

}  // namespace mjc::protocol
