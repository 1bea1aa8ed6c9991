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
inline constexpr std::uint16_t kVersion = 2;

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
  kGuard = 3,     // the CAN node's own protective setting (a timeout, the heartbeat):
                  // applied at once, refused while a motion runs
  kJointLimit = 4,  // the joint's own limit, from its robot description: applied by the
                    // tick while idle, and only ever tightened; a reset (the image's
                    // ceiling) is the only way back to a looser one
};

// Whether a write to a parameter of this access is refused while a motion runs (a
// calibration sweep, a trial, a stream, or a start awaiting its verdict): everything
// that protects the wearer or the board. The telemetry rates may change mid-motion.
constexpr bool RefusedWhileMoving(ParamAccess access) {
  return access == ParamAccess::kGuard || access == ParamAccess::kControl ||
         access == ParamAccess::kJointLimit;
}

namespace param_detail {
inline constexpr std::int64_t kI32Max = std::numeric_limits<std::int32_t>::max();
inline constexpr std::int64_t kI32Min = std::numeric_limits<std::int32_t>::min();
}  // namespace param_detail

// --- the protections' bounds --------------------------------------------------------
// Every parameter that protects the wearer or the board has a range that keeps the
// protection on; the board refuses a write outside it, naming the bound (ParamStatus).

// The heartbeat: every tool reads the board's state and clock from it and takes a board
// without one for 10 s as silent, so a board whose heartbeat stopped could not be
// reached by the tool that would restart it. At least 10 Hz, the default: the tools'
// waits assume a heartbeat within 100 ms (board_client.h, Patience). At most 1 kHz: a
// heartbeat at the tick rate alone would take more than a 1 Mbit/s classical bus.
inline constexpr std::int64_t kHeartbeatMinHz = 10;
inline constexpr std::int64_t kHeartbeatMaxHz = 1000;
// Host supervision: at least two host heartbeat periods (the tools send one every
// 100 ms), so that one late heartbeat does not stop every motion; at most 1 s, the
// longest a motion may run on with its commanding tool dead: half a cycle of the
// paper's 0.5 Hz trials, where the default (300 ms) keeps `./bench`'s orphan_motion_s
// under its 0.5 s goal.
inline constexpr std::int64_t kHostTimeoutMinMs = 200;
inline constexpr std::int64_t kHostTimeoutMaxMs = 1000;
// Streamed setpoints: at most 100 ms, the goal for lost commands (a motor whose host
// stopped streaming stops within it); at least 1 ms, a tick's resolution.
inline constexpr std::int64_t kStreamTimeoutMinMs = 1;
inline constexpr std::int64_t kStreamTimeoutMaxMs = 100;
// The SEA torque ceiling compiled into the image, N·m: the largest rated torque a
// Maestro joint's description may carry (robots/README.md, limits.torque_Nm: (0, 5]).
// The description's own, sent by the tools (joint_torque_limit), is tighter.
inline constexpr Torque kTorqueCeiling = Torque::FromDouble(5.0);
// The joint angle ceiling, rad: the board's ±1.6 rad (±91.7°) joint range, which every
// description's travel lies within (limits.extension_deg, limits.flexion_deg).
inline constexpr Angle kJointAngleCeiling = Angle::FromDouble(1.6);
// The joint velocity ceiling, rad/s: the supervisor's default (SupervisorConfig); the
// paper's largest motion, 25° at 0.5 Hz, peaks at 1.4 rad/s. A lab may tighten it.
inline constexpr AngularVelocity kVelocityCeiling = AngularVelocity::FromDouble(5.0);
// The position loop's gains: at most ten times the gains tuned for the Maestro joint
// (app/joint_config.h: kp 40 1/rad, ki 200 1/(rad·s), kd 0.05 s/rad, kff 0.095 s/rad):
// room to retune a joint, while a gain typed in the wrong unit (a thousandfold) that
// would drive the motor to its duty limit on the first count of error is refused.
inline constexpr std::int64_t kPositionKpMaxRaw = 400 << 16;
inline constexpr std::int64_t kPositionKiMaxRaw = 2000 << 16;
inline constexpr std::int64_t kPositionKdMaxRaw = 32768;   // 0.5 s/rad
inline constexpr std::int64_t kPositionKffMaxRaw = 62259;  // 0.95 s/rad, rounded down

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
  X(kHeartbeatHz, 0x0105, "heartbeat_hz", "Hz", 0, kHeartbeatMinHz, kHeartbeatMaxHz,     \
    kGuard, "rate of the Heartbeat (the tools need it: it cannot be stopped)")           \
  X(kStreamTimeoutMs, 0x0110, "stream_timeout_ms", "ms", 0, kStreamTimeoutMinMs,         \
    kStreamTimeoutMaxMs, kGuard,                                                         \
    "streamed setpoints older than this stop the motor (fault 301)")                     \
  X(kHostTimeoutMs, 0x0111, "host_timeout_ms", "ms", 0, kHostTimeoutMinMs,               \
    kHostTimeoutMaxMs, kGuard,                                                           \
    "a motion whose host session is silent this long stops (fault 302)")                 \
  X(kPositionKp, 0x0200, "position_kp", "1/rad", 16, 0, kPositionKpMaxRaw, kControl,     \
    "position loop: duty per rad of error")                                              \
  X(kPositionKi, 0x0201, "position_ki", "1/(rad.s)", 16, 0, kPositionKiMaxRaw, kControl, \
    "position loop: duty per rad.s of integrated error")                                 \
  X(kPositionKd, 0x0202, "position_kd", "s/rad", 16, 0, kPositionKdMaxRaw, kControl,     \
    "position loop: duty per rad/s of motor velocity")                                   \
  X(kPositionKff, 0x0203, "position_kff", "s/rad", 16, 0, kPositionKffMaxRaw, kControl,  \
    "position loop: duty per rad/s of setpoint velocity")                                \
  X(kVelocityWindow, 0x0210, "velocity_window", "ticks", 0,                              \
    VelocityEstimator::kMinWindow, ControlTick::kMaxVelocityWindow, kControl,            \
    "joint velocity estimator's window (odd; its delay aligns the torque)")              \
  X(kAttachmentPriorStiffness, 0x0211, "attachment_prior_stiffness", "N.m/rad",          \
    Stiffness::kFracBits, 0, param_detail::kI32Max, kControl,                            \
    "attachment k the velocity model assumes until a trial's window is fitted")          \
  X(kAttachmentPriorDamping, 0x0212, "attachment_prior_damping", "N.m.s/rad",            \
    Damping::kFracBits, 0, param_detail::kI32Max, kControl,                              \
    "attachment b the velocity model assumes until a trial's window is fitted")          \
  X(kTorqueMax, 0x0300, "torque_max", "N.m", Torque::kFracBits, 1, kTorqueCeiling.raw(), \
    kControl, "SEA torque limit (fault 202 beyond it), within joint_torque_limit")       \
  X(kJointTorqueLimit, 0x0301, "joint_torque_limit", "N.m", Torque::kFracBits, 1,        \
    kTorqueCeiling.raw(), kJointLimit,                                                   \
    "the joint's rated SEA torque (its description's limits.torque_Nm): torque_max "     \
    "never exceeds it")                                                                  \
  X(kJointAngleMin, 0x0302, "joint_angle_min", "rad", Angle::kFracBits,                  \
    -kJointAngleCeiling.raw(), -1, kJointLimit,                                          \
    "the joint's extension limit (its description's limits.extension_deg; fault 200)")   \
  X(kJointAngleMax, 0x0303, "joint_angle_max", "rad", Angle::kFracBits, 1,               \
    kJointAngleCeiling.raw(), kJointLimit,                                               \
    "the joint's flexion limit (its description's limits.flexion_deg; fault 200)")       \
  X(kVelocityMax, 0x0304, "velocity_max", "rad/s", AngularVelocity::kFracBits, 1,        \
    kVelocityCeiling.raw(), kControl, "joint velocity limit (fault 203 beyond it)")      \
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
inline constexpr std::uint32_t kParamListDigest = 3798214345;
template <std::uint32_t kDigest>
constexpr bool ParamListIs() {
  static_assert(kDigest == kParamListDigest,
                "protocol/params.h: the parameter list changed; see kParamListDigest");
  return true;
}
static_assert(ParamListIs<ParamListDigest()>());

}  // namespace mjc::protocol
