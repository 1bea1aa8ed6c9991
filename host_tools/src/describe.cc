#include "mjc/host/describe.h"

#include <cstdio>

#include "mjc/boot/image_header.h"

namespace mjc::host {

std::string_view FaultName(Fault fault) {
  switch (fault) {
    case Fault::kNone:
      return "none";
    case Fault::kJointParity:
      return "joint encoder parity error";
    case Fault::kJointErrorFlag:
      return "joint encoder error flag";
    case Fault::kJointJump:
      return "joint angle jumped";
    case Fault::kJointStuck:
      return "joint encoder stuck";
    case Fault::kMotorStuck:
      return "motor stalled or its encoder stuck";
    case Fault::kJointAngleLimit:
      return "joint angle limit";
    case Fault::kMotorAngleLimit:
      return "motor angle limit";
    case Fault::kTorqueLimit:
      return "torque limit";
    case Fault::kVelocityLimit:
      return "joint velocity limit";
    case Fault::kTickOverrun:
      return "control tick overrun";
    case Fault::kCommandTimeout:
      return "streamed setpoints stopped";
    case Fault::kHostHeartbeatLost:
      return "host heartbeat lost";
    case Fault::kBoardStartup:
      return "board start-up failed";
    case Fault::kCanBusOff:
      return "CAN bus-off";
    case Fault::kEmergencyStop:
      return "emergency stop";
  }
  return "unknown fault";
}

std::string DescribeFault(Fault fault) {
  return std::to_string(static_cast<unsigned>(fault)) + " (" +
         std::string(FaultName(fault)) + ")";
}

std::string_view OutcomeName(protocol::CommandOutcomeCode outcome) {
  using protocol::CommandOutcomeCode;
  switch (outcome) {
    case CommandOutcomeCode::kAccepted:
      return "accepted";
    case CommandOutcomeCode::kRefusedNotIdle:
      return "the board is not idle";
    case CommandOutcomeCode::kRefusedUncalibrated:
      return "the board holds no calibration";
    case CommandOutcomeCode::kRefusedInvalid:
      return "invalid configuration";
    case CommandOutcomeCode::kRefusedFaultActive:
      return "a fault is latched or its cause is still present";
    case CommandOutcomeCode::kRefusedBusy:
      return "an earlier request is still being applied";
  }
  return "unknown outcome";
}

namespace {
// The common part: "6.0° × 3 at 0.50 Hz, rest 1.5 s".
std::string Oscillation(Angle amplitude, std::uint16_t frequency_mHz,
                        std::uint8_t repetitions, std::uint8_t rest_100ms) {
  char text[96];
  std::snprintf(text, sizeof text, "%.1f° × %u at %.2f Hz, rest %.1f s",
                amplitude.ToDouble() * 180.0 / 3.14159265358979323846,
                static_cast<unsigned>(repetitions), frequency_mHz / 1000.0,
                rest_100ms / 10.0);
  return text;
}
}  // namespace

std::string DescribeConfig(const protocol::TrialConfig& config) {
  return Oscillation(config.amplitude, config.frequency_mHz, config.repetitions,
                     config.rest_100ms);
}

std::string DescribeConfig(const protocol::SweepConfig& config) {
  return "sweep to " + Oscillation(config.end_amplitude, config.frequency_mHz,
                                   config.repetitions, config.rest_100ms);
}

std::string_view MotionName(std::uint8_t start_code) {
  switch (static_cast<protocol::CommandCode>(start_code)) {
    case protocol::CommandCode::kStartTrial:
      return "trial";
    case protocol::CommandCode::kStartSweep:
      return "calibration sweep";
    case protocol::CommandCode::kStartStream:
      return "stream";
    default:
      return "motion";
  }
}

std::string_view ParamStatusName(protocol::ParamStatus status) {
  using protocol::ParamStatus;
  switch (status) {
    case ParamStatus::kOk:
      return "ok";
    case ParamStatus::kUnknown:
      return "unknown parameter";
    case ParamStatus::kOutOfRange:
      return "out of range, or refused by the board's check of its whole control "
             "configuration";
    case ParamStatus::kRefusedNotIdle:
      return "a motion runs (the protections and the control parameters change only "
             "while the board is idle)";
    case ParamStatus::kReadOnly:
      return "read-only";
    case ParamStatus::kRefusedBusy:
      return "an earlier write or calibration is still being applied: try again";
    case ParamStatus::kBelowMinimum:
      return "below its minimum";
    case ParamStatus::kAboveMaximum:
      return "above its maximum (the image's ceiling)";
    case ParamStatus::kBeyondJointLimit:
      return "beyond the joint's limit the board holds (from its robot description; "
             "only a reset of the board loosens it)";
  }
  return "unknown status";
}

std::string_view StateName(protocol::BoardState state) {
  switch (state) {
    case protocol::BoardState::kIdle:
      return "idle";
    case protocol::BoardState::kCalibrating:
      return "calibrating";
    case protocol::BoardState::kRunning:
      return "running";
    case protocol::BoardState::kFault:
      return "FAULT";
  }
  return "?";
}

std::string_view ImageName(protocol::ImageKind image) {
  return image == protocol::ImageKind::kBootloader ? "bootloader" : "application";
}

std::string_view ResetCauseName(protocol::ResetCause cause) {
  switch (cause) {
    case protocol::ResetCause::kPowerOn:
      return "power-on";
    case protocol::ResetCause::kPin:
      return "reset pin";
    case protocol::ResetCause::kSoftware:
      return "software";
    case protocol::ResetCause::kWatchdog:
      return "watchdog";
    case protocol::ResetCause::kOther:
      return "other";
    case protocol::ResetCause::kUnknown:
      break;
  }
  return "unknown";
}

std::string BuildName(std::uint32_t commit, bool dirty) {
  char hex[16];
  std::snprintf(hex, sizeof hex, "%08x", commit);
  return std::string(hex) + (dirty ? "+dirty" : "");
}

std::string_view BootStateName(protocol::BootState state) {
  switch (state) {
    case protocol::BootState::kHoldWindow:
      return "hold window";
    case protocol::BootState::kReady:
      return "ready";
    case protocol::BootState::kReceiving:
      return "receiving";
    case protocol::BootState::kCommitted:
      return "committed";
  }
  return "?";
}

std::string_view StayReasonName(protocol::StayReason reason) {
  switch (reason) {
    case protocol::StayReason::kNone:
      return "not staying";
    case protocol::StayReason::kNoValidImage:
      return "no valid image";
    case protocol::StayReason::kRequested:
      return "asked by the application";
    case protocol::StayReason::kHoldFrame:
      return "held by a host";
    case protocol::StayReason::kBootLoop:
      return "boot loop: 3 starts unconfirmed";
    case protocol::StayReason::kUpdate:
      return "update begun";
    case protocol::StayReason::kNoClock:
      return "no crystal clock";
  }
  return "?";
}

std::string_view ClockSourceName(protocol::ClockSource source) {
  switch (source) {
    case protocol::ClockSource::kHsi16:
      return "HSI16";
    case protocol::ClockSource::kHsePll:
      return "crystal";
    case protocol::ClockSource::kHsiPll:
      return "HSI16 PLL";
    case protocol::ClockSource::kOther:
      break;
  }
  return "other";
}

std::vector<std::string> ChipWarnings(const protocol::ChipInfo& chip) {
  std::vector<std::string> out;
  if (protocol::BootsFromPin(chip.option_bytes)) {
    out.push_back(
        "boots from its BOOT0 pin (option bytes nSWBOOT0 = 1): a high PB8 starts ST's "
        "ROM "
        "bootloader, which has no CAN");
  }
  if (chip.clock != protocol::ClockSource::kHsePll) {
    std::string w = "runs on " + std::string(ClockSourceName(chip.clock)) +
                    ", not its crystal (±1 % instead of ppm; ";
    w += chip.hse_ready ? "the crystal started late" : "the crystal does not run";
    out.push_back(w + ")");
  }
  return out;
}

std::string_view BootErrorName(protocol::BootError error) {
  using E = protocol::BootError;
  // The image checks have the same numbers and names (mjc::boot::ImageCheck).
  const auto code = static_cast<std::uint8_t>(error);
  if (code >= 1 && code <= 9)
    return boot::ImageCheckName(static_cast<boot::ImageCheck>(code));
  switch (error) {
    case E::kNone:
      return "none";
    case E::kNoImage:
    case E::kBadHeader:
    case E::kWrongBoard:
    case E::kWrongHardware:
    case E::kBadLength:
    case E::kBadLoadAddress:
    case E::kBadVectors:
    case E::kImageCrc:
    case E::kUnreadable:
      break;
    case E::kNotReceiving:
      return "not_receiving";
    case E::kUnexpectedOffset:
      return "unexpected_offset";
    case E::kBadChunk:
      return "bad_chunk";
    case E::kOutOfRegion:
      return "out_of_region";
    case E::kFlashError:
      return "flash_error";
    case E::kIncomplete:
      return "incomplete";
    case E::kTransfer:
      return "transfer";
    case E::kBadRequest:
      return "bad_request";
    case E::kNothingToBoot:
      return "nothing_to_boot";
    case E::kMotionRunning:
      return "motion_running";
  }
  return "unknown";
}

std::string DescribeBootStatus(const protocol::BootStatus& status) {
  using protocol::BootState;
  using protocol::StayReason;
  switch (status.state) {
    case BootState::kHoldWindow:
    case BootState::kCommitted:
      return std::string(BootStateName(status.state));
    case BootState::kReceiving:
      return "receiving " + std::to_string(status.progress_permille / 10) + "%";
    case BootState::kReady:
      break;
  }
  std::string why(StayReasonName(status.reason));
  if (status.error != protocol::BootError::kNone &&
      (status.reason == StayReason::kNoValidImage ||
       status.reason == StayReason::kUpdate)) {
    why += ": " + std::string(BootErrorName(status.error));
  }
  return "ready (" + why + ")";
}

std::string SilentNode(int node, std::string_view iface) {
  return "node " + std::to_string(node) + " is silent (is the board powered and on " +
         std::string(iface) + "? try mjc list)";
}

std::string DescribeCalibrationResult(protocol::CalibrationResult result,
                                      std::uint8_t detail) {
  using R = protocol::CalibrationResult;
  switch (result) {
    case R::kAccepted:
      return "accepted";
    case R::kWrongSize:
      return "wrong record size";
    case R::kBadMagic:
      return "not a calibration record";
    case R::kUnsupportedVersion:
      return "unsupported record version";
    case R::kBadCrc:
      return "bad CRC (corrupted in transit)";
    case R::kRefusedNotIdle:
      return "the board is not idle";
    case R::kReassemblyError:
      return "ISO-TP transfer failed (" + std::to_string(detail) + ")";
    case R::kStorageFailed:
      return "applied, but the board could not store it in flash";
    case R::kRefusedBusy:
      return "the board is still applying an earlier change: try again";
    case R::kOutOfRange:
      // The detail is the CalibrationError, whose low codes are the backlash's.
      switch (detail) {
        case static_cast<std::uint8_t>(BacklashConfigError::kAlphaOutOfRange):
          return "alpha outside (1/8, 8)";
        case static_cast<std::uint8_t>(BacklashConfigError::kOffsetOutOfRange):
          return "an offset outside ±28.6° (0.5 rad)";
        case static_cast<std::uint8_t>(BacklashConfigError::kLeftAboveRight):
          return "c_left above c_right";
        case static_cast<std::uint8_t>(BacklashConfigError::kFrictionOutOfRange):
          return "cable friction outside [0, 5] N·m";
        case static_cast<std::uint8_t>(CalibrationError::kStiffness):
          return "SEA stiffness outside (0, 100] N·m/rad";
        case static_cast<std::uint8_t>(CalibrationError::kJointZero):
          return "joint zero count outside 0..16383";
        default:
          return "a value out of range (" + std::to_string(detail) + ")";
      }
  }
  return "unknown result " + std::to_string(static_cast<int>(result));
}

}  // namespace mjc::host
