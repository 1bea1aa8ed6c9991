// Calibrations on the host: the JSON file `mjc calibrate` writes and `mjc cal` reads
// (angles in degrees, for people), its upload to a board over ISO-TP, and the
// calibration in force read back from a board.
#pragma once

#include <cstdint>
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "mjc/host/board_client.h"
#include "mjc/host/calibration_fit.h"
#include "mjc/host/robot_description.h"
#include "mjc/protocol/calibration_record.h"

namespace mjc::host {

// What a Maestro joint plausibly has: α = r_m / r_j within [0.5, 2] and an SEA stiffness
// within a decade of the default joint's 0.63 N·m/rad (CalibrationFromJson warns outside
// them; a robot description, robot_description.h, is refused outside them).
inline constexpr double kPlausibleAlpha[2] = {0.5, 2.0};
inline constexpr double kPlausibleStiffness[2] = {0.063, 6.3};  // N·m/rad

// A cable friction in N·m, [0, 5], on the record's mN·m grid (what a board then holds
// and reads back), for a calibration file and a robot description alike.
Torque CableFrictionForRecord(double friction_Nm);

nlohmann::json CalibrationToJson(const protocol::CalibrationRecord& record);

// The keys of a calibration file, as CalibrationToJson writes them.
inline constexpr std::string_view kCalibrationKeys[] = {
    "c_right_deg",      "c_left_deg",   "alpha",      "sea_stiffness_Nm_per_rad",
    "joint_zero_count", "fit_rms_urad", "fit_lag_us", "fitted_at_unix_s",
    "cable_friction_Nm"};

// Reads and range-checks a calibration (the board's own checks, run here first): nullopt
// with the reason naming the field when it is missing, of the wrong type or out of
// range, or a key that is not a calibration's (named with the key it resembles:
// mjc/strict_json.h). The fit fields (fit_rms_urad, fit_lag_us, fitted_at_unix_s) are
// optional (absent: 0) but, when present, must be integers within their wire type's
// range. Values the board accepts but no Maestro joint has (an offset beyond ±10°, α
// outside [0.5, 2], a stiffness beyond a decade of the SEA's 0.63 N·m/rad) are kept and
// each is described in *warnings, one line each, with the plausible range and why.
// Never throws.
std::optional<protocol::CalibrationRecord> CalibrationFromJson(
    const nlohmann::json& json, std::string* why,
    std::vector<std::string>* warnings = nullptr);

enum class UploadStatus : std::uint8_t {
  kAnswered = 0,        // the board answered: see result and detail
  kLinkFailed = 1,      // the ISO-TP socket could not be opened or the record not sent
  kNoAnswer = 2,        // no answer within the timeout (absent or silent node)
  kMalformedReply = 3,  // an answer that is not the 2-byte [result, detail]
};

struct UploadOutcome {
  UploadStatus status = UploadStatus::kNoAnswer;
  protocol::CalibrationResult result = protocol::CalibrationResult::kAccepted;
  std::uint8_t detail = 0;
  double elapsed_ms = 0;  // the last transfer's
  int transfers = 0;      // transfers made (more than one: see kMostReassemblyRetries)
};

// A board that answers kReassemblyError lost the transfer itself (a consecutive frame
// late beyond its ISO-TP timeout, out of sequence) and applied nothing: the uploads below
// send the record again, up to this many times, before they return that answer. A
// sender starved of CPU on a loaded host is the usual cause; a bus that keeps breaking
// transfers still ends in the answer.
inline constexpr int kMostReassemblyRetries = 3;

// Uploads `record` to `node` on `iface` (ISO-TP on the node's 0x3E/0x3F ids) and waits
// for the board's answer as long as Patience{timeout_ms} allows: timeout_ms of the
// board's own time (its heartbeats' ticks: a board simulated slower than real time,
// programming its flash, is given its time), or the default silence with no frame from
// it. Unless the status is kAnswered, *why says what went wrong.
UploadOutcome UploadCalibration(const std::string& iface, int node,
                                const protocol::CalibrationRecord& record, int timeout_ms,
                                std::string* why);

// The same upload on a CAN link of the node's bus that has no kernel ISO-TP (the
// simulator's in-process bus): the record segmented as ISO 15765-2 on classical frames
// on `isotp` (first frame, the board's flow control honoured, consecutive frames), and
// the board's answer awaited as above, by `board`'s patience (its clock, its silence).
// `isotp` is given over to the transfer: its filters are set to the node's answers.
UploadOutcome UploadCalibration(BoardClient& board, CanLink& isotp,
                                const protocol::CalibrationRecord& record, int timeout_ms,
                                std::string* why);

// The board's angle telemetry over the calibration sweep it has just started, recorded
// as `mjc calibrate` and the paper's scenarios record it: every angle sample `board`
// receives until the board leaves kCalibrating. Followed at the board's pace (Patience):
// at most twice the sweep's `length_s` in the board's time, plus 2 s, and the board may
// not fall silent. `each`, when given, runs on every pass of the wait with the samples
// it has just taken (none, often): a caller's progress line, and the record written as
// it arrives. The samples are kept however the wait ended.
struct SweepSamples {
  std::vector<double> motor_rad, joint_rad;
  bool ended = false;  // the board left kCalibrating; if not, `end` and *why say how
  WaitEnd end{};
  std::uint64_t malformed = 0;  // frames `board` found malformed while recording
};
SweepSamples RecordSweep(BoardClient& board, double length_s,
                         const std::function<void(std::span<const AngleSample>)>& each,
                         std::string* why);

// A calibration sweep fitted and turned into the record to upload, as `mjc calibrate`
// does it (and the paper's scenarios and the virtual board's rig, through this one
// function):
// - the fit: the play operator with the joint's first-order lag (FitBacklash with
//   fit_lag, the angles recorded at `rate_hz`, legal > 0); α = 1 without a `robot`, or
//   the description's (searched within ±kAlphaFitSpan of it with `fit_alpha`), and the
//   joint angles shifted from the zero of the board's `held` record to the
//   description's (JointZeroShift);
// - the record: `held` with the fitted backlash (ToFirmwareConfig), the fit's RMS and
//   lag (the cable friction `held` has), and with a `robot` its SEA stiffness, cable
//   friction and joint zero (UseRobotJoint).
//   fitted_at_unix_s is left as in `held`, for the caller to stamp.
// `record` is empty when the fit is not usable, and `why` says why (the fit's own
// refusal or the firmware's range).
struct SweepCalibration {
  BacklashFit fit;
  std::optional<protocol::CalibrationRecord> record;
  std::string why;
};
SweepCalibration FitSweep(std::span<const double> motor_rad,
                          std::vector<double> joint_rad, double rate_hz,
                          const protocol::CalibrationRecord& held,
                          const RobotDescription* robot, bool fit_alpha);

// A calibration sweep run on `board` (idle, on the robot alone) and fitted, with mjc
// calibrate's steps but none of its files, progress or emergency stop: the record in
// force read (the new one keeps what it holds), the angle telemetry's rate read,
// `sweep` configured and started, its samples recorded (RecordSweep, the patience from
// the sweep's own length) and fitted (FitSweep with `robot` and `fit_alpha`). How the
// paper's scenarios and the virtual board's tests calibrate a board over the bus.
struct SweepRun {
  SweepSamples samples;                    // as recorded, however the sweep ended
  std::optional<SweepCalibration> fitted;  // once the samples were fitted
  std::string error;  // empty: fitted->record is the record to upload; else why not
};
SweepRun RunSweep(BoardClient& board, const protocol::SweepConfig& sweep,
                  const RobotDescription* robot, bool fit_alpha);

struct BoardCalibration {
  // c_r, c_l, α, stiffness and joint zero count in force. The fit fields are not
  // readable over the bus and stay 0.
  protocol::CalibrationRecord record;
  bool calibrated = false;  // false: the board runs on its built-in values
};

// Reads the calibration in force from a board (its read-only calibration parameters,
// 500 ms per read). nullopt with the first failure's reason.
std::optional<BoardCalibration> ReadCalibration(BoardClient& board, std::string* why);

}  // namespace mjc::host
