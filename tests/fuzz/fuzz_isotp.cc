// Any sequence of frames into the board's ISO-TP receiver, at any times: nothing
// crashes, a completed payload never exceeds the buffer or its announced length.
#include <cstdint>
#include <cstring>

#include "mjc/protocol/isotp.h"

using namespace mjc::protocol;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  IsoTpReceiver rx(0x3F1);
  std::uint32_t now = 0;
  std::size_t i = 0;
  while (i + 2 <= size) {
    CanFrame f;
    f.id = 0x3E1;
    f.length = static_cast<std::uint8_t>(data[i] % 9);
    now += data[i + 1] * 8u;  // up to 2 s between frames: timeouts too
    i += 2;
    const std::size_t n = std::min<std::size_t>(f.length, size - i);
    std::memcpy(f.data.data(), data + i, n);
    i += n;
    rx.Poll(now);
    CanFrame reply;
    const IsoTpEvent e = rx.Handle(f, now, &reply);
    if (e == IsoTpEvent::kComplete && rx.payload().size() > IsoTpReceiver::kCapacity) {
      __builtin_trap();
    }
    if (reply.length > 8) __builtin_trap();
  }
  return 0;
}
