// Any frame, through every message decoder and the board's CAN node: nothing crashes,
// a decoded message re-encodes to a frame that decodes identically, and the node
// accounts for every frame (handled, ignored, malformed or a malformed ISO-TP
// frame).
#include <cstdint>
#include <cstring>
#include <tuple>

#include "mjc/app/joint_board.h"
#include "mjc/protocol/codec.h"

using namespace mjc;
using namespace mjc::protocol;

namespace {

struct QuietIo {
  Sample ISR_Read() { return Sample{}; }
  void ISR_Write(const Actuation&) {}
};

template <class M>
void RoundTrip(const CanFrame& f) {
  M m;
  if (Decode(f, &m) != DecodeError::kOk) return;
  const CanFrame again = Encode(m, NodeOf(f.id));
  M back;
  if (Decode(again, &back) != DecodeError::kOk) __builtin_trap();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  // The firmware's board, without a bus: frames go straight to its CAN node (each must
  // be accounted for), and its main loop's pass runs after every tick.
  static app::JointBoard board(app::JointBoardConfig{}, nullptr, nullptr);
  static QuietIo io;
  app::CanNode& node = board.node();
  // A stream of frames: [id_hi id_lo len flags data(len)]...
  std::size_t i = 0;
  while (i + 4 <= size) {
    CanFrame f;
    f.id = ((static_cast<std::uint32_t>(data[i]) << 8) | data[i + 1]) & 0x7FFu;
    f.length = static_cast<std::uint8_t>(data[i + 2] % 65);
    f.fd = (data[i + 3] & 1u) != 0;
    i += 4;
    const std::size_t n = std::min<std::size_t>(f.length, size - i);
    std::memcpy(f.data.data(), data + i, n);
    i += n;
    std::apply([&](auto... m) { (RoundTrip<decltype(m)>(f), ...); }, AllMessages{});
    const std::uint32_t before = node.counters().received();
    node.HandleFrame(f);
    if (node.counters().received() != before + 1) {
      __builtin_trap();  // a frame not accounted for
    }
    board.ISR_Tick(io);
    board.Poll();
  }
  return 0;
}
