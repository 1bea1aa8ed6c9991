#include "mjc/host/calibration_io.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <utility>

#include "mjc/host/can_link.h"
#include "mjc/host/describe.h"
#include "mjc/host/units.h"
#include "mjc/protocol/can_frame.h"
#include "mjc/protocol/messages.h"
#include "mjc/strict_json.h"

namespace mjc::host {
namespace {

// What a Maestro joint plausibly has (see CalibrationFromJson).
// The backlash a Maestro joint plausibly has, each side: more than two counts of its
// 14-bit joint encoder (360°·2/16384 = 0.044°; less is below what a sweep resolves,
// and is what radians typed into a degree field look like: the paper's 1.1° is 0.0192
// rad) and at most 20° (a cable's slack is a few degrees; more is degrees of a radian
// slip, or a slack no finger should be driven through).
constexpr double kPlausibleOffsetDeg = 20;
constexpr double kLeastOffsetDeg = 2 * 360.0 / 16384;

}  // namespace

Torque CableFrictionForRecord(double friction_Nm) {
  return protocol::CableFrictionFromMilliNm(
      static_cast<std::uint16_t>(std::lround(friction_Nm * 1000.0)));
}

nlohmann::json CalibrationToJson(const protocol::CalibrationRecord& r) {
  return {{"c_right_deg", RadToDeg(r.backlash.c_right.ToDouble())},
          {"c_left_deg", RadToDeg(r.backlash.c_left.ToDouble())},
          {"alpha", r.backlash.alpha.ToDouble()},
          {"sea_stiffness_Nm_per_rad", r.sea_stiffness.ToDouble()},
          {"cable_friction_Nm",
           protocol::CableFrictionMilliNm(r.backlash.cable_friction) / 1000.0},
          {"joint_zero_count", r.joint_zero_count},
          {"fit_rms_urad", r.fit_rms_urad},
          {"fit_lag_us", r.fit_lag_us},
          {"fitted_at_unix_s", r.fitted_at_unix_s}};
}

std::optional<protocol::CalibrationRecord> CalibrationFromJson(
    const nlohmann::json& j, std::string* why, std::vector<std::string>* warnings) {
  protocol::CalibrationRecord r;
  if (!j.is_object()) {
    *why = "calibration: the top level must be an object";
    return std::nullopt;
  }
  if (const auto unknown = strict::UnknownKey(j, kCalibrationKeys)) {
    *why = "calibration: " + *unknown;
    return std::nullopt;
  }
  auto number = [&](const char* key, double* out) {
    if (!j.contains(key) || !j[key].is_number()) {
      *why = std::string("calibration: field '") + key + "' missing or not a number";
      return false;
    }
    *out = j[key].get<double>();
    if (!std::isfinite(*out)) {
      *why = std::string("calibration: field '") + key + "' is not finite";
      return false;
    }
    return true;
  };
  // An integer field in 0..max, as the record's unsigned wire fields hold them; absent
  // is 0 unless required.
  auto integer = [&](const char* key, std::uint64_t max, bool required, auto* out) {
    *out = 0;
    if (!j.contains(key) && !required) return true;
    const bool in_range =
        j.contains(key) && j[key].is_number_integer() &&
        (j[key].is_number_unsigned() || j[key].get<std::int64_t>() >= 0) &&
        j[key].get<std::uint64_t>() <= max;
    if (!in_range) {
      *why = std::string("calibration: field '") + key + "' must be an integer in 0.." +
             std::to_string(max);
      return false;
    }
    *out = static_cast<std::remove_pointer_t<decltype(out)>>(j[key].get<std::uint64_t>());
    return true;
  };
  using U32 = std::numeric_limits<std::uint32_t>;
  double c_right = 0, c_left = 0, alpha = 0, stiffness = 0;
  double friction = 0;  // absent: not modelled (a file from before the field)
  if (!number("c_right_deg", &c_right) || !number("c_left_deg", &c_left) ||
      !number("alpha", &alpha) || !number("sea_stiffness_Nm_per_rad", &stiffness) ||
      !integer("joint_zero_count", 16383, true, &r.joint_zero_count) ||
      !integer("fit_rms_urad", U32::max(), false, &r.fit_rms_urad) ||
      !integer("fit_lag_us", U32::max(), false, &r.fit_lag_us) ||
      !integer("fitted_at_unix_s", std::numeric_limits<std::uint64_t>::max(), false,
               &r.fitted_at_unix_s) ||
      (j.contains("cable_friction_Nm") && !number("cable_friction_Nm", &friction))) {
    return std::nullopt;
  }
  if (friction < 0 || friction > kMaxCableFriction.ToDouble()) {
    char text[128];
    std::snprintf(text, sizeof text,
                  "calibration: field 'cable_friction_Nm' = %g is outside [0, %g] N·m",
                  friction, kMaxCableFriction.ToDouble());
    *why = text;
    return std::nullopt;
  }
  r.backlash.c_right = Angle::Quantize(DegToRad(c_right));
  r.backlash.c_left = Angle::Quantize(DegToRad(c_left));
  r.backlash.alpha = Scale::Quantize(alpha);
  r.sea_stiffness = Stiffness::Quantize(stiffness);
  r.backlash.cable_friction = CableFrictionForRecord(friction);
  // The board's checks, run here first, so a bad file never reaches the bus.
  const auto bytes = protocol::EncodeCalibration(r);
  protocol::CalibrationRecord checked;
  std::uint8_t detail = 0;
  const auto result = protocol::DecodeCalibration(bytes, &checked, &detail);
  if (result != protocol::CalibrationResult::kAccepted) {
    *why = "calibration refused: " + DescribeCalibrationResult(result, detail);
    return std::nullopt;
  }
  // What the board accepts is wider than what a Maestro joint has: said, not refused,
  // since another robot may differ, but a unit slip (radians typed as degrees, a
  // stiffness in N/m) shows here before it reaches a finger.
  if (warnings != nullptr) {
    char line[320];
    for (const auto& [key, value] :
         {std::pair{"c_right_deg", c_right}, std::pair{"c_left_deg", c_left}}) {
      if (std::abs(value) > kPlausibleOffsetDeg) {
        std::snprintf(line, sizeof line,
                      "calibration: %s = %g° is beyond the plausible ±%g°: the Bowden "
                      "cable's slack is a few degrees (the paper's joint: +1.1°/-0.9°); "
                      "radians written as degrees? (the board accepts up to ±28.6°)",
                      key, value, kPlausibleOffsetDeg);
        warnings->push_back(line);
      } else if (std::abs(value) < kLeastOffsetDeg) {
        std::snprintf(line, sizeof line,
                      "calibration: %s = %g° is below two counts of the 14-bit joint "
                      "encoder (%.3f°), less slack than a sweep can resolve: radians "
                      "written in a degree field? (%g rad is %.2f°)",
                      key, value, kLeastOffsetDeg, value, RadToDeg(value));
        warnings->push_back(line);
      }
    }
    if (alpha < kPlausibleAlpha[0] || alpha > kPlausibleAlpha[1]) {
      std::snprintf(line, sizeof line,
                    "calibration: alpha = %g is outside the plausible [%g, %g]: the "
                    "backlash's slope is 1 for a cable of equal sides (the board "
                    "accepts (1/8, 8))",
                    alpha, kPlausibleAlpha[0], kPlausibleAlpha[1]);
      warnings->push_back(line);
    }
    if (stiffness < kPlausibleStiffness[0] || stiffness > kPlausibleStiffness[1]) {
      std::snprintf(line, sizeof line,
                    "calibration: sea_stiffness_Nm_per_rad = %g is outside the plausible "
                    "[%g, %g] N·m/rad, a decade either side of the Maestro SEA's 0.63 "
                    "(2·3150 N/m·(10 mm)²); N/m instead of N·m/rad? (the board accepts "
                    "(0, 100])",
                    stiffness, kPlausibleStiffness[0], kPlausibleStiffness[1]);
      warnings->push_back(line);
    }
  }
  return checked;
}

namespace {

// Sends again while the board answers that the transfer itself failed.
template <class Once>
UploadOutcome WithRetries(const Once& once) {
  UploadOutcome out;
  for (int transfer = 1;; ++transfer) {
    out = once();
    out.transfers = transfer;
    if (out.status != UploadStatus::kAnswered ||
        out.result != protocol::CalibrationResult::kReassemblyError ||
        transfer > kMostReassemblyRetries) {
      return out;
    }
  }
}

UploadOutcome UploadOnce(const std::string& iface, int node,
                         const protocol::CalibrationRecord& record, int timeout_ms,
                         std::string* why) {
  using protocol::Function;
  const auto n = static_cast<std::uint8_t>(node);
  UploadOutcome out;
  // The board's clock, from its heartbeats on a raw socket opened before the record
  // goes out.
  auto raw = SocketCanLink::Open(iface, why);
  if (!raw) {
    out.status = UploadStatus::kLinkFailed;
    return out;
  }
  BoardClient board(raw.get(), n);
  auto link = IsoTpLink::Open(
      iface, protocol::MakeId(static_cast<std::uint8_t>(Function::kIsoTpToBoard), n),
      protocol::MakeId(static_cast<std::uint8_t>(Function::kIsoTpFromBoard), n), why);
  const auto t0 = std::chrono::steady_clock::now();
  if (!link || !link->Send(protocol::EncodeCalibration(record), why)) {
    out.status = UploadStatus::kLinkFailed;
    return out;
  }
  std::optional<std::vector<std::uint8_t>> reply;
  bool failed = false;
  std::string isotp_why;
  const auto over = [&] {
    if (!reply && !failed) reply = link->Receive(0, &isotp_why, &failed);
    return reply.has_value() || failed;
  };
  WaitEnd end{};
  const bool ended =
      board.Await(over, Patience{std::chrono::milliseconds(timeout_ms)}, &end, why);
  out.elapsed_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0)
          .count();
  if (!reply) {
    if (failed) *why = isotp_why;
    out.status = ended || end != WaitEnd::kLinkFailed ? UploadStatus::kNoAnswer
                                                      : UploadStatus::kLinkFailed;
    return out;
  }
  if (reply->size() != 2) {
    out.status = UploadStatus::kMalformedReply;
    *why = "node " + std::to_string(node) + " answered with " +
           std::to_string(reply->size()) + " bytes, not [result, detail]";
    return out;
  }
  out.status = UploadStatus::kAnswered;
  out.result = static_cast<protocol::CalibrationResult>((*reply)[0]);
  out.detail = (*reply)[1];
  return out;
}

UploadOutcome UploadOnce(BoardClient& board, CanLink& isotp,
                         const protocol::CalibrationRecord& record, int timeout_ms,
                         std::string* why) {
  using protocol::CanFrame;
  using protocol::Function;
  const std::uint8_t n = board.node();
  const std::uint32_t to_board =
      protocol::MakeId(static_cast<std::uint8_t>(Function::kIsoTpToBoard), n);
  const std::uint32_t from_board =
      protocol::MakeId(static_cast<std::uint8_t>(Function::kIsoTpFromBoard), n);
  UploadOutcome out;
  const IdFilter answers{from_board, 0x7FF};
  if (!isotp.SetFilters({&answers, 1}, why)) {
    out.status = UploadStatus::kLinkFailed;
    return out;
  }
  while (isotp.Receive(0)) {
  }  // heard before the record went out: no answer to it
  const auto bytes = protocol::EncodeCalibration(record);
  const auto t0 = std::chrono::steady_clock::now();
  const Patience patience{std::chrono::milliseconds(timeout_ms)};
  std::optional<CanFrame> got;
  // The board's next ISO-TP frame, within the patience; false with the reason.
  const auto next = [&](WaitEnd* end) {
    got.reset();
    const auto arrived = [&] {
      if (!got) {
        if (const ReceiveResult r = isotp.Receive(0)) got = r->frame;
      }
      return got.has_value();
    };
    return board.Await(arrived, patience, end, why);
  };
  const auto fail = [&](UploadStatus status) {
    out.status = status;
    out.elapsed_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0)
            .count();
    return out;
  };
  CanFrame f;
  f.id = to_board;
  f.length = 8;
  f.data[0] = static_cast<std::uint8_t>(0x10u | (bytes.size() >> 8));
  f.data[1] = static_cast<std::uint8_t>(bytes.size());
  std::copy_n(bytes.begin(), 6, f.data.begin() + 2);
  if (!isotp.Send(f, why)) return fail(UploadStatus::kLinkFailed);
  std::size_t at = 6;
  std::uint8_t sequence = 1;
  WaitEnd end{};
  while (at < bytes.size()) {
    // Flow control: continue (with a block size), wait, or overflow.
    if (!next(&end)) {
      return fail(end == WaitEnd::kLinkFailed ? UploadStatus::kLinkFailed
                                              : UploadStatus::kNoAnswer);
    }
    const std::uint8_t pci = got->data[0];
    if ((pci & 0xF0u) != 0x30u) continue;  // not flow control: not for this transfer
    if ((pci & 0x0Fu) == 1) continue;      // wait: the next flow control follows
    if ((pci & 0x0Fu) != 0) {
      *why = "node " + std::to_string(n) +
             " refused the record's transfer (flow status " +
             std::to_string(pci & 0x0Fu) + ")";
      return fail(UploadStatus::kLinkFailed);
    }
    const std::size_t block = got->data[1];
    for (std::size_t k = 0; at < bytes.size() && (block == 0 || k < block); ++k) {
      const std::size_t size = std::min<std::size_t>(7, bytes.size() - at);
      f.length = static_cast<std::uint8_t>(size + 1);
      f.data[0] = static_cast<std::uint8_t>(0x20u | sequence);
      std::copy_n(bytes.begin() + static_cast<std::ptrdiff_t>(at), size,
                  f.data.begin() + 1);
      if (!isotp.Send(f, why)) return fail(UploadStatus::kLinkFailed);
      at += size;
      sequence = static_cast<std::uint8_t>((sequence + 1) & 0x0Fu);
    }
  }
  // The answer: one single frame.
  do {
    if (!next(&end)) {
      return fail(end == WaitEnd::kLinkFailed ? UploadStatus::kLinkFailed
                                              : UploadStatus::kNoAnswer);
    }
  } while ((got->data[0] & 0xF0u) != 0x00u);
  if (got->data[0] != 2 || got->length < 3) {
    *why = "node " + std::to_string(n) + " answered with " +
           std::to_string(got->data[0] & 0x0Fu) + " bytes, not [result, detail]";
    return fail(UploadStatus::kMalformedReply);
  }
  out = fail(UploadStatus::kAnswered);
  out.result = static_cast<protocol::CalibrationResult>(got->data[1]);
  out.detail = got->data[2];
  return out;
}

}  // namespace

UploadOutcome UploadCalibration(const std::string& iface, int node,
                                const protocol::CalibrationRecord& record, int timeout_ms,
                                std::string* why) {
  return WithRetries([&] { return UploadOnce(iface, node, record, timeout_ms, why); });
}

UploadOutcome UploadCalibration(BoardClient& board, CanLink& isotp,
                                const protocol::CalibrationRecord& record, int timeout_ms,
                                std::string* why) {
  return WithRetries([&] { return UploadOnce(board, isotp, record, timeout_ms, why); });
}

SweepSamples RecordSweep(BoardClient& board, double length_s,
                         const std::function<void(std::span<const AngleSample>)>& each,
                         std::string* why) {
  SweepSamples out;
  const std::uint64_t malformed_before = board.malformed();
  board.TakeAngles();  // samples kept earlier, if any, are not this sweep's
  board.KeepAngles(true);
  const auto take_samples = [&] {
    const auto taken = board.TakeAngles();
    for (const AngleSample& a : taken) {
      out.motor_rad.push_back(a.motor_rad);
      out.joint_rad.push_back(a.joint_rad);
    }
    if (each) each(taken);
  };
  const Patience patience{
      std::chrono::milliseconds(static_cast<long>(2000 * length_s) + 2000)};
  out.ended = board.AwaitMotionEnd(protocol::BoardState::kCalibrating, take_samples,
                                   patience, &out.end, why);
  board.KeepAngles(false);
  out.malformed = board.malformed() - malformed_before;
  return out;
}

SweepCalibration FitSweep(std::span<const double> motor_rad,
                          std::vector<double> joint_rad, double rate_hz,
                          const protocol::CalibrationRecord& held,
                          const RobotDescription* robot, bool fit_alpha) {
  // The joint trails the cable side by a few ms on the robot alone (the SEA spring
  // against the joint's damping): fit that lag too, or it reads as extra slack.
  BacklashFitOptions options;
  options.fit_lag = true;
  options.sample_rate_hz = rate_hz;
  if (robot != nullptr) {
    UseRobotAlpha(*robot, fit_alpha, &options);
    // Recorded with the zero the board holds; fitted as with the joint's own.
    const double shift = JointZeroShift(held.joint_zero_count, *robot);
    for (double& j : joint_rad) j += shift;
  }
  SweepCalibration out;
  out.fit = FitBacklash(motor_rad, joint_rad, options);
  const auto backlash = ToFirmwareConfig(out.fit, &out.why);
  if (!backlash) return out;
  protocol::CalibrationRecord record = held;
  record.backlash = *backlash;
  record.backlash.cable_friction = held.backlash.cable_friction;  // not the fit's
  if (robot != nullptr) UseRobotJoint(*robot, &record);
  record.fit_rms_urad =
      static_cast<std::uint32_t>(std::lround(out.fit.rms_error_rad * 1e6));
  record.fit_lag_us = static_cast<std::uint32_t>(std::lround(out.fit.lag_s * 1e6));
  out.record = record;
  return out;
}

SweepRun RunSweep(BoardClient& board, const protocol::SweepConfig& sweep,
                  const RobotDescription* robot, bool fit_alpha) {
  SweepRun out;
  std::string why;
  const auto held = ReadCalibration(board, &why);
  if (!held) {
    out.error = "cannot read the calibration in force: " + why;
    return out;
  }
  const auto rate_hz = board.ReadParam(protocol::ParamId::kTelemetryAnglesHz, 500, &why);
  if (!rate_hz || *rate_hz <= 0) {
    out.error = "no angle telemetry to fit: " + why;
    return out;
  }
  // The sweep and the start naming it; the board's MotionConfig confirms it.
  const auto started = board.Start(sweep, kStartAnswerMs, &why);
  if (started != protocol::CommandOutcomeCode::kAccepted) {
    out.error = board.motion_mismatch() ? board.mismatch()
                : started               ? "the board refused the calibration sweep: " +
                                board.RefusalMessage(*started)
                          : "the board refused the calibration sweep: " + why;
    // Whatever runs that is not this sweep is stopped, and nothing of it recorded.
    const bool wrong = board.motion_mismatch();
    board.ReleaseMotion();
    if (wrong) (void)board.Command(protocol::CommandCode::kStop, 1000, &why);
    return out;
  }
  const double length_s =
      sweep.repetitions / (sweep.frequency_mHz / 1000.0) + 2 * sweep.rest_100ms / 10.0;
  out.samples = RecordSweep(board, length_s, {}, &why);
  board.ReleaseMotion();
  if (!out.samples.ended && out.samples.end == WaitEnd::kWrongMotion) {
    out.error = "the sweep did not run as sent, stopped: " + why;
    out.samples = {};
    (void)board.Command(protocol::CommandCode::kStop, 1000, &why);
    return out;
  }
  if (!out.samples.ended) {
    out.error = "the sweep did not end: " + why;
    return out;
  }
  if (board.status().state == protocol::BoardState::kFault) {
    out.error = "the sweep faulted: fault " + DescribeFault(board.status().fault);
    return out;
  }
  // A lost sample shifts every later one in time: the lag fit would read it as lag.
  if (out.samples.malformed != 0) {
    out.error = "malformed angle frames during the sweep: not fitting it";
    return out;
  }
  out.fitted = FitSweep(out.samples.motor_rad, out.samples.joint_rad, *rate_hz,
                        held->record, robot, fit_alpha);
  if (!out.fitted->record) out.error = "calibration refused: " + out.fitted->why;
  return out;
}

std::optional<BoardCalibration> ReadCalibration(BoardClient& board, std::string* why) {
  using protocol::ParamId;
  std::int32_t value[7] = {};
  const ParamId ids[7] = {ParamId::kCalibrated,           ParamId::kCalibrationRight,
                          ParamId::kCalibrationLeft,      ParamId::kCalibrationAlpha,
                          ParamId::kCalibrationStiffness, ParamId::kCalibrationJointZero,
                          ParamId::kCalibrationFriction};
  for (int i = 0; i < 7; ++i) {
    const auto v = board.ReadParam(ids[i], 500, why);
    if (!v) return std::nullopt;
    value[i] = *v;
  }
  if (value[5] < 0 || value[5] > 16383) {
    *why = "node " + std::to_string(board.node()) + " reports joint zero count " +
           std::to_string(value[5]) + ", outside 0..16383";
    return std::nullopt;
  }
  BoardCalibration out;
  out.calibrated = value[0] == 1;
  out.record.backlash.c_right = Angle::FromRaw(value[1]);
  out.record.backlash.c_left = Angle::FromRaw(value[2]);
  out.record.backlash.alpha = Scale::FromRaw(value[3]);
  out.record.sea_stiffness = Stiffness::FromRaw(value[4]);
  out.record.joint_zero_count = static_cast<std::uint16_t>(value[5]);
  out.record.backlash.cable_friction = Torque::FromRaw(value[6]);
  return out;
}

}  // namespace mjc::host
