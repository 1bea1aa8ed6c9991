// Names for the protocol's stable codes, for what the tools print: a fault code or a
// command outcome alone says little to someone at the bench.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "mjc/core/control_tick.h"
#include "mjc/core/supervisor.h"
#include "mjc/protocol/calibration_record.h"
#include "mjc/protocol/messages.h"

namespace mjc::host {

// What the fault means in a few words ("CAN bus-off"); "unknown fault" for a code this
// build does not know (a newer board's).
std::string_view FaultName(Fault fault);
// "303 (CAN bus-off)": the stable code first, as logs and scripts match it.
std::string DescribeFault(Fault fault);

// "idle", "calibrating", "running", "FAULT".
std::string_view StateName(protocol::BoardState state);
// "application" or "bootloader".
std::string_view ImageName(protocol::ImageKind image);
// "power-on", "reset pin", "software", "watchdog", "other", "unknown".
std::string_view ResetCauseName(protocol::ResetCause cause);
// A build as the boards and mjc --version print it: 8 hex digits, "+dirty" when built
// from a tree with uncommitted changes ("1958ba84+dirty").
std::string BuildName(std::uint32_t commit, bool dirty);

// The bootloader's words: its state ("hold window", "ready", "receiving",
// "committed"), why it stays ("no valid image", "held by a host", …) and its errors by
// their stable names ("image_crc", "unexpected_offset", …; the image checks' names are
// mjc-image's).
std::string_view BootStateName(protocol::BootState state);
std::string_view StayReasonName(protocol::StayReason reason);
// "crystal", "HSI16 PLL", "HSI16", "other".
std::string_view ClockSourceName(protocol::ClockSource source);
// What mjc list warns about a board from its bootloader's ChipInfo: one that samples
// its BOOT0 pin at reset (nSWBOOT0 = 1), one that does not run on its crystal.
std::vector<std::string> ChipWarnings(const protocol::ChipInfo& chip);
std::string_view BootErrorName(protocol::BootError error);
// A BootStatus in a few words, as mjc list shows a board in its bootloader: "ready (no
// valid image: no_image)", "ready (held by a host)", "receiving 41%", "committed".
std::string DescribeBootStatus(const protocol::BootStatus& status);

// The one wording of an absent or silent node, with the checks to make: "node 5 is
// silent (is the board powered and on vcan0? try mjc list)".
std::string SilentNode(int node, std::string_view iface);

// A motion's configuration in a few words: "6.0° × 3 at 0.50 Hz, rest 1.5 s" (a trial),
// "sweep to 30.0° × 10 at 1.50 Hz, rest 0.5 s".
std::string DescribeConfig(const protocol::TrialConfig& config);
std::string DescribeConfig(const protocol::SweepConfig& config);
// "trial", "calibration sweep", "stream" for a start's code; "motion" otherwise.
std::string_view MotionName(std::uint8_t start_code);

// Why the board refused a command ("the board is not idle"), or "accepted".
std::string_view OutcomeName(protocol::CommandOutcomeCode outcome);

// The board's answer to a parameter write: "ok", or why it refused it ("the board is
// not idle (control parameters change only while it is)", "read-only", …).
std::string_view ParamStatusName(protocol::ParamStatus status);

// The board's answer to a calibration upload ("accepted", "bad CRC (corrupted in
// transit)", "c_left above c_right", …); `detail` names the field out of range.
std::string DescribeCalibrationResult(protocol::CalibrationResult result,
                                      std::uint8_t detail);

}  // namespace mjc::host
