// The calibration record: what `mjc calibrate` uploads over ISO-TP and the board
// validates, applies and (later) persists. Little-endian, fixed layout:
//
//   offset size field
//        0    4 magic 'MJCC' (0x43434A4D)
//        4    2 schema version (2; version 1 is still read, see below)
//        6    2 payload length (bytes after this header, before the CRC): 36
//        8    4 c_r, Q7.24 rad            (BacklashConfig.c_right)
//       12    4 c_l, Q7.24 rad            (BacklashConfig.c_left)
//       16    4 α, Q3.28                  (BacklashConfig.alpha)
//       20    4 2·k·r_j², Q7.24 N·m/rad   (ControlConfig.sea_stiffness)
//       24    2 joint encoder zero count (0..16383)
//       26    2 τ_f, the sheath's friction at the joint, mN·m (BacklashConfig.
//                cable_friction; 0: not modelled)
//       28    4 fit RMS, µrad
//       32    4 fitted joint lag, µs
//       36    8 time of the fit, Unix seconds
//       44    4 CRC-32 (IEEE 802.3, as zlib's crc32) of bytes 0..43
//
// Version 1 had bytes 26..27 reserved (0) and is otherwise the same: a record stored
// or written before version 2 reads with τ_f = 0, the operator it was fitted for.
//
// The board answers every upload with a single ISO-TP frame [result, detail].
#pragma once

#include <array>
#include <cstdint>
#include <span>

#include "mjc/core/backlash.h"
#include "mjc/core/control_tick.h"
#include "mjc/core/quantities.h"
#include "mjc/protocol/crc32.h"

namespace mjc::protocol {

inline constexpr std::uint32_t kCalibrationMagic = 0x43434A4Du;  // "MJCC"
inline constexpr std::uint16_t kCalibrationVersion = 2;
inline constexpr std::uint16_t kCalibrationVersionWithoutFriction = 1;
inline constexpr std::size_t kCalibrationRecordSize = 48;

struct CalibrationRecord {
  BacklashConfig backlash;
  Stiffness sea_stiffness = Stiffness::FromDouble(0.63);
  std::uint16_t joint_zero_count = 0;
  std::uint32_t fit_rms_urad = 0;
  std::uint32_t fit_lag_us = 0;
  std::uint64_t fitted_at_unix_s = 0;
};

// Stable codes, sent back to the host as the first byte of the reply.
enum class CalibrationResult : std::uint8_t {
  kAccepted = 0,
  kWrongSize = 1,
  kBadMagic = 2,
  kUnsupportedVersion = 3,
  kBadCrc = 4,
  kOutOfRange = 5,  // detail: the CalibrationError (mjc/core/control_tick.h)
  kRefusedNotIdle = 6,
  kReassemblyError = 7,  // the ISO-TP transfer itself failed (sequence, timeout)
  kStorageFailed = 8,    // applied, but writing it to flash failed: not kept over a reset
  kRefusedBusy = 9,      // the previous calibration or parameter write is still pending
};

// τ_f on the wire, in mN·m: Torque to the nearest mN·m (saturating at 0 and 65.535
// N·m, both beyond what Validate accepts) and back to the nearest Q7.24. A friction
// already on the mN·m grid goes through a record unchanged; the host puts the
// description's on that grid before it builds a record (a read-back then compares).
std::uint16_t CableFrictionMilliNm(Torque friction);
Torque CableFrictionFromMilliNm(std::uint16_t milli_nm);

std::array<std::uint8_t, kCalibrationRecordSize> EncodeCalibration(
    const CalibrationRecord& r);

// Checks size, magic, version, CRC, then every value's range (through the firmware's
// own validators); *out is written only when the result is kAccepted.
CalibrationResult DecodeCalibration(std::span<const std::uint8_t> bytes,
                                    CalibrationRecord* out, std::uint8_t* detail);

}  // namespace mjc::protocol
