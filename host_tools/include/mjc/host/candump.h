// The candump log format: one CAN frame a line, as can-utils' `candump -L` prints it
// and canplayer, log2asc, Wireshark and python-can read it:
//
//   (1699999999.123456) vcan0 123#DEADBEEF      classical, 11-bit id, 0..8 data bytes
//   (1699999999.123456) vcan0 12345678#CAFE     classical, 29-bit id (8 hex digits)
//   (1699999999.123456) vcan0 321#R3            remote frame, optional DLC 0..8
//   (1699999999.123456) vcan0 123##5AABBCCDD    CAN FD: one hex digit of flags, 0..64
//   bytes (1699999999.123456) vcan0 20000004#0004...  error frame (id with CAN_ERR_FLAG)
//   (1699999999.123456) vcan0 123#0011223344556677_C   8 bytes with DLC 9..15 (len8_dlc)
//
// Seconds and exactly six digits of microseconds since the epoch; the interface padded
// on the left when candump records several (spaces); with candump -x a trailing " R" or
// " T" (received, transmitted); data bytes may be separated by '.' (as cansend takes
// them). Written here from linux/can.h's frame layout and can-utils' lib.c format:
// Debian ships no library that parses it (can-utils' parser is compiled into its
// tools, python-can's is Python).
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "mjc/protocol/can_frame.h"

namespace mjc::host {

// One line's frame, in linux/can.h's terms.
struct CandumpFrame {
  std::int64_t timestamp_us = 0;  // since the epoch, 0..999999999999999999
  std::string interface;          // 1..15 characters (IFNAMSIZ − 1), no blanks
  // Identifier and flags as struct can_frame's can_id: an 11-bit id, or a 29-bit one
  // with CAN_EFF_FLAG; CAN_RTR_FLAG on a remote frame; an error frame is CAN_ERR_FLAG
  // with its error class bits (CAN_ERR_MASK).
  std::uint32_t can_id = 0;
  bool fd = false;          // a CAN FD frame ("##")
  std::uint8_t flags = 0;   // CAN FD only: CANFD_BRS, CANFD_ESI, CANFD_FDF (0..15)
  std::uint8_t length = 0;  // data bytes: 0..8 classical (a remote frame's DLC), 0..64 FD
  std::uint8_t len8_dlc = 0;  // classical 8-byte frames only: a DLC of 9..15, else 0
  std::array<std::uint8_t, 64> data{};

  bool operator==(const CandumpFrame&) const = default;
};

// Parses one line (a trailing "\n" or "\r\n" is allowed). nullopt with a one-line
// reason in *why (naming the field and what was found) for anything candump would not
// have written; never throws.
std::optional<CandumpFrame> ParseCandumpLine(std::string_view line, std::string* why);

// The line candump -L prints for `frame` (single space after the timestamp, no
// trailing newline): ParseCandumpLine reads it back equal. `frame` must be one that
// ParseCandumpLine could return.
std::string FormatCandumpLine(const CandumpFrame& frame);

// The protocol's view of a data frame with an 11-bit id (classical or FD); nullopt for
// a remote, error or 29-bit frame, which the protocol never sends.
std::optional<protocol::CanFrame> ToProtocolFrame(const CandumpFrame& frame);

}  // namespace mjc::host
