// A CAN or CAN FD frame as the protocol sees it: 11-bit identifier, length, payload.
// Transports (SocketCAN on the host, FDCAN on the G474, the in-process bus of the
// tests) convert to and from their own frame types.
#pragma once

#include <array>
#include <cstdint>

namespace mjc::protocol {

struct CanFrame {
  std::uint32_t id = 0;     // 11-bit standard identifier
  std::uint8_t length = 0;  // bytes: 0..8 classic, FD lengths up to 64
  bool fd = false;          // a CAN FD frame (only TelemetryAngleBatch travels as one)
  std::array<std::uint8_t, 64> data{};
};

// Node ids of the Maestro's joints. 0 addresses every node: only the broadcast
// messages (messages.h: StopAll) carry it.
inline constexpr std::uint8_t kMinNode = 1;
inline constexpr std::uint8_t kMaxNode = 8;
inline constexpr std::uint8_t kEveryNode = 0;

// 11-bit identifiers: function code (7 bits) above the node id (4 bits). Lower
// identifiers win arbitration, so the function codes are ordered by urgency.
constexpr std::uint32_t MakeId(std::uint8_t function, std::uint8_t node) {
  return (static_cast<std::uint32_t>(function & 0x7Fu) << 4) | (node & 0x0Fu);
}
constexpr std::uint8_t FunctionOf(std::uint32_t id) {
  return static_cast<std::uint8_t>((id >> 4) & 0x7Fu);
}
constexpr std::uint8_t NodeOf(std::uint32_t id) {
  return static_cast<std::uint8_t>(id & 0x0Fu);
}

}  // namespace mjc::protocol
