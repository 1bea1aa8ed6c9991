// Any text as lines of a candump log (what mjc log --from reads): each line is refused
// with a reason or parsed into a frame that keeps linux/can.h's limits, and a parsed
// frame formats to the line candump would print, which parses back to the same frame.
#include <linux/can.h>

#include <cstdint>
#include <string>
#include <string_view>

#include "mjc/host/candump.h"

namespace {

void Check(std::string_view line) {
  std::string why;
  const auto frame = mjc::host::ParseCandumpLine(line, &why);
  if (!frame) {
    if (why.empty()) __builtin_trap();  // a refusal always says why
    return;
  }
  const mjc::host::CandumpFrame& f = *frame;
  const bool error = (f.can_id & CAN_ERR_FLAG) != 0;
  const bool extended = (f.can_id & CAN_EFF_FLAG) != 0;
  const bool remote = (f.can_id & CAN_RTR_FLAG) != 0;
  if (f.interface.empty() || f.interface.size() > 15) __builtin_trap();
  if (f.interface.find_first_of(" \t") != std::string::npos) __builtin_trap();
  if (f.length > (f.fd ? CANFD_MAX_DLEN : CAN_MAX_DLEN)) __builtin_trap();
  if (f.flags > 15 || (!f.fd && f.flags != 0)) __builtin_trap();
  if (error && (extended || remote || f.fd)) __builtin_trap();
  if (!error && !extended && (f.can_id & ~CAN_RTR_FLAG) > CAN_SFF_MASK) __builtin_trap();
  if (remote && f.fd) __builtin_trap();
  if (f.len8_dlc != 0 &&
      (f.fd || f.length != CAN_MAX_DLEN || f.len8_dlc < 9 || f.len8_dlc > 15)) {
    __builtin_trap();
  }
  for (std::size_t i = remote ? 0 : f.length; i < f.data.size(); ++i) {
    if (f.data[i] != 0) __builtin_trap();  // nothing beyond the frame's bytes
  }
  const auto protocol = mjc::host::ToProtocolFrame(f);
  if (protocol && (error || extended || remote || protocol->id > CAN_SFF_MASK)) {
    __builtin_trap();
  }
  // candump's spelling of the frame reads back as the same frame, and is a fixed point.
  const std::string text = mjc::host::FormatCandumpLine(f);
  const auto again = mjc::host::ParseCandumpLine(text, &why);
  if (!again || !(*again == f)) __builtin_trap();
  if (mjc::host::FormatCandumpLine(*again) != text) __builtin_trap();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  std::size_t start = 0;
  while (start <= text.size()) {
    const std::size_t end = text.find('\n', start);
    Check(text.substr(start, end == std::string_view::npos ? end : end - start + 1));
    if (end == std::string_view::npos) break;
    start = end + 1;
  }
  return 0;
}
