// The bootloader's bus intake (BootHold, BootCommand, its ISO-TP channel: begin,
// chunks, commit, boot) on any sequence of frames, with the board's clock stepped
// between them, over a flash with the STM32G4's rules, with and without a valid image
// installed. Invariants (a trap otherwise): nothing outside the application region is
// ever erased or programmed, and whenever the bootloader would hand over, the region
// holds an image whose header and CRC check out (recomputed here from the bytes).
//
// Input: byte 0 bit 0 = a valid image installed first; then records of
//   [ms to step (0-255)] [id low] [id high: 3 bits] [length 0-8] [length bytes].
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <vector>

#include "hal/sim/sim_flash.h"
#include "mjc/boot/bootloader.h"
#include "mjc/protocol/crc32.h"
#include "mjc/protocol/little_endian.h"

namespace {

using namespace mjc;
using namespace mjc::boot;

constexpr std::uint8_t kNode = 2;

// The simulated flash, trapping on any write outside the application region.
class GuardedFlash final : public hal::Flash {
 public:
  hal::SimFlash sim{256};

 private:
  static void Check(std::uint32_t page) {
    if (page < kG474Layout.app_first_page ||
        page >= kG474Layout.app_first_page + kG474Layout.app_pages) {
      std::abort();
    }
  }
  hal::FlashResult DoErasePage(std::uint32_t page) override {
    Check(page);
    return sim.ErasePage(page);
  }
  hal::FlashResult DoProgram(std::uint32_t page, std::uint32_t offset,
                             std::uint64_t value) override {
    Check(page);
    return sim.ProgramDoubleWord(page, offset, value);
  }
  hal::FlashResult DoRead(std::uint32_t page, std::uint32_t offset,
                          std::span<std::uint8_t> out) const override {
    return sim.Read(page, offset, out);
  }
  std::uint32_t DoPageCount() const override { return 256; }
};

class Port final : public hal::CanPort {
 public:
  std::vector<protocol::CanFrame> in;
  std::size_t next = 0;

 private:
  bool DoSend(const protocol::CanFrame&) override { return true; }
  bool DoReceive(protocol::CanFrame* f) override {
    if (next >= in.size()) return false;
    *f = in[next++];
    return true;
  }
  std::uint32_t DoTakeBusOff() override { return 0; }
  hal::CanPortCounters DoCounters() const override { return {}; }
};

// A small valid image for the G474 layout, written as a debugger would.
void InstallImage(hal::SimFlash& flash) {
  std::vector<std::uint8_t> image(64, 0x5A);
  protocol::PutLe(&image[0], 0x10000800u, 4);
  protocol::PutLe(&image[4], kG474Layout.ImageAddress() + 9u, 4);
  ImageHeader h;
  h.board_type = 1;
  h.hardware_min = h.hardware_max = 1;
  h.length = 64;
  h.image_crc = protocol::Crc32(image);
  h.load_address = kG474Layout.ImageAddress();
  const HeaderBytes header = EncodeHeader(h);
  (void)flash.ErasePage(8);
  for (std::uint32_t at = 0; at < kHeaderSize; at += 8) {
    (void)flash.ProgramDoubleWord(8, at, protocol::GetLe(&header[at], 8));
  }
  for (std::uint32_t at = 0; at < image.size(); at += 8) {
    (void)flash.ProgramDoubleWord(8, 512 + at, protocol::GetLe(&image[at], 8));
  }
}

// The region's header and image, checked from the bytes alone.
bool RegionHoldsAValidImage(const hal::SimFlash& flash) {
  HeaderBytes header{};
  (void)flash.Read(8, 0, header);
  ImageHeader h;
  if (DecodeHeader(header, &h) != ImageCheck::kValid || h.length > 120 * 2048 - 512) {
    return false;
  }
  std::vector<std::uint8_t> image(h.length);
  for (std::uint32_t at = 0; at < h.length;) {
    const std::uint32_t offset = (512 + at) % 2048;
    const std::uint32_t n = std::min<std::uint32_t>(h.length - at, 2048 - offset);
    (void)flash.Read(8 + (512 + at) / 2048, offset,
                     std::span<std::uint8_t>(image).subspan(at, n));
    at += n;
  }
  return protocol::Crc32(image) == h.image_crc;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  GuardedFlash flash;
  if (data[0] & 1u) InstallImage(flash.sim);
  Port port;
  BootHandoff handoff{};
  BootloaderConfig config;
  config.layout = kG474Layout;
  config.board_type = 1;
  config.hardware_revision = 1;
  config.node = kNode;
  Bootloader boot(config, &flash, &port, &handoff);
  std::uint32_t now = 0;
  BootAction action = boot.Start(now, (data[0] & 2u) != 0);
  std::size_t at = 1;
  while (action != BootAction::kBoot && at + 4 <= size) {
    now += data[at];
    protocol::CanFrame f;
    f.id = data[at + 1] | (static_cast<std::uint32_t>(data[at + 2] & 7u) << 8);
    f.length = static_cast<std::uint8_t>(data[at + 3] % 9u);
    at += 4;
    for (std::size_t i = 0; i < f.length && at < size; ++i) f.data[i] = data[at++];
    port.in.push_back(f);
    action = boot.Poll(now);
  }
  for (int i = 0; action == BootAction::kNone && i < 3; ++i)
    action = boot.Poll(now += 100);
  if (action == BootAction::kBoot && !RegionHoldsAValidImage(flash.sim)) std::abort();
  return 0;
}
