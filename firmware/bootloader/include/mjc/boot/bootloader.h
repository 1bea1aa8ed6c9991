// The CAN bootloader's logic, the same on the G474, on QEMU and in the host's tests:
// what to do at reset, and the update protocol on the bus. The board's image
// (firmware/boards/g474_bootloader) owns the drivers, the clock and the hand-over.
//
// At reset (Start):
//   1. the stay request in the handoff block is taken (read and erased);
//   2. the installed image is checked (header, board, vectors, CRC of every byte);
//   3. it stays — answering on the bus with the board's node id — when the image is not
//      valid, when the board's clock is not the designed one (no crystal: the board
//      serves the bus on its internal oscillator but never starts the application on
//      it), when the application asked (a valid stay request after a software
//      reset), or when the image has been started kMaxBootAttempts times without
//      confirming a healthy start (a watchdog reset loop);
//   4. otherwise it listens for a BootHold for the hold window (200 ms of its own
//      clock), and boots when none came: the attempt is counted, then Poll returns
//      kBoot and the board hands over.
//
// The update (on the bus, BOOTLOADER.md has the sequence and timeouts):
//   Begin (ISO-TP: the new image's 128-byte header) → checked against this board before
//     anything is erased; then the header's page is erased first, so that from here on
//     no valid image is in flash until the commit;
//   Chunk (ISO-TP: offset, 8..248 bytes, a multiple of 8) in order: each page is erased
//     when the first chunk reaches it, each double-word programmed once;
//   Commit → the CRC of the image as it now is in flash must match the header's; then
//     the header is programmed, its last double-word (CRC + commit mark) last, and the
//     whole check of step 2 must pass;
//   Boot → Poll returns kReset 20 ms later (the answer leaves first) and the reset
//     starts the new image through step 1-4.
//
// Every erase and program goes through AppRegion (nothing outside the application
// region). Errors answer the request with a stable BootError and change nothing that
// could make a partial image bootable. No heap; the chunk buffer is the ISO-TP
// receiver's (256 bytes).
#pragma once

#include <array>
#include <cstdint>
#include <span>

#include "hal/can_port.h"
#include "hal/flash.h"
#include "mjc/boot/app_region.h"
#include "mjc/boot/handoff.h"
#include "mjc/boot/image_check.h"
#include "mjc/boot/layout.h"
#include "mjc/protocol/can_frame.h"
#include "mjc/protocol/isotp.h"
#include "mjc/protocol/messages.h"

namespace mjc::boot {

// ImageCheck's numbers are BootError's.
constexpr bool SameNumber(ImageCheck check, protocol::BootError error) {
  return static_cast<int>(check) == static_cast<int>(error);
}
static_assert(SameNumber(ImageCheck::kNoImage, protocol::BootError::kNoImage) &&
              SameNumber(ImageCheck::kBadHeader, protocol::BootError::kBadHeader) &&
              SameNumber(ImageCheck::kWrongBoard, protocol::BootError::kWrongBoard) &&
              SameNumber(ImageCheck::kWrongHardware,
                         protocol::BootError::kWrongHardware) &&
              SameNumber(ImageCheck::kBadLength, protocol::BootError::kBadLength) &&
              SameNumber(ImageCheck::kBadLoadAddress,
                         protocol::BootError::kBadLoadAddress) &&
              SameNumber(ImageCheck::kBadVectors, protocol::BootError::kBadVectors) &&
              SameNumber(ImageCheck::kImageCrc, protocol::BootError::kImageCrc) &&
              SameNumber(ImageCheck::kUnreadable, protocol::BootError::kUnreadable));
constexpr protocol::BootError ToBootError(ImageCheck c) {
  return static_cast<protocol::BootError>(static_cast<std::uint8_t>(c));
}

// The ISO-TP requests' layout (the first byte is the BootRequest's number).
//   Begin: [0] 2, [1] sequence, [2..3] 0, [4..131] the image header
//   Chunk: [0] 3, [1] sequence, [2..3] 0, [4..7] image offset (LE), [8..] 8..248 bytes
inline constexpr std::size_t kRequestHeaderBytes = 4;
inline constexpr std::size_t kBeginBytes = kRequestHeaderBytes + kHeaderSize;
inline constexpr std::size_t kChunkDataOffset = 8;
inline constexpr std::size_t kMaxChunkData =
    protocol::IsoTpReceiver::kCapacity - kChunkDataOffset;
static_assert(kBeginBytes <= protocol::IsoTpReceiver::kCapacity);
static_assert(kMaxChunkData == 248 && kMaxChunkData % 8 == 0,
              "a chunk is whole double-words");

struct BootloaderConfig {
  BootLayout layout;
  std::uint16_t board_type = 0;
  std::uint8_t hardware_revision = 0;
  std::uint8_t node = 1;  // 1..8
  // What the BoardInfo says about this bootloader (image = kBootloader).
  std::uint32_t build = 0;
  bool dirty = false;
  std::uint16_t instance = 0;
  protocol::ResetCause reset_cause = protocol::ResetCause::kUnknown;
  std::uint32_t hold_window_ms = 200;  // 0: no window (boot at once: the QEMU test)
  ServiceHook service = nullptr;       // during long flash work (the watchdog)
  // False: the board's clock did not come up as designed (no crystal); it stays
  // (StayReason::kNoClock) whatever the image.
  bool clock_ok = true;
  // The chip's report, sent after every BoardInfo; null: none (a board without one).
  protocol::ChipInfo (*chip_info)() = nullptr;
};

enum class BootAction : std::uint8_t {
  kNone = 0,   // keep polling
  kBoot = 1,   // hand over to the image now (boot_image() says where)
  kReset = 2,  // reset the chip (a host's Boot: the reset starts the new image)
};

class Bootloader {
 public:
  static constexpr std::uint32_t kHoldWindowMs = 200;
  static constexpr std::uint32_t kStatusPeriodMs = 100;
  static constexpr std::uint32_t kInfoPeriodMs = 1000;
  static constexpr std::uint32_t kResetDelayMs = 20;
  static constexpr std::uint32_t kMaxBootAttempts = 3;
  static constexpr std::size_t kOutboxFrames = 8;

  Bootloader(const BootloaderConfig& config, hal::Flash* flash, hal::CanPort* can,
             volatile BootHandoff* handoff);

  // Once, at reset. `software_reset`: the reset was a software request (a stay request
  // counts only then). kBoot at once only with no hold window.
  BootAction Start(std::uint32_t now_ms, bool software_reset);

  // The main loop: frames in, timers, frames out. `now_ms` is the board's clock.
  BootAction Poll(std::uint32_t now_ms);

  protocol::BootState state() const { return state_; }
  protocol::StayReason reason() const { return reason_; }
  protocol::BootError error() const { return error_; }
  // The image checked at Start (or after a commit).
  const InstalledImage& image() const { return image_; }
  // Where the image's vector table is (what the hand-over gives VTOR).
  std::uint32_t boot_address() const { return config_.layout.ImageAddress(); }
  std::uint16_t progress_permille() const;
  std::uint32_t frames_dropped() const { return dropped_; }

 private:
  void HandleFrame(const protocol::CanFrame& frame, std::uint32_t now_ms);
  void HandleIsoTp(const protocol::CanFrame& frame, std::uint32_t now_ms);
  void HandleRequest(std::span<const std::uint8_t> request);
  protocol::BootError Begin(std::span<const std::uint8_t, kHeaderSize> header);
  protocol::BootError Chunk(std::uint32_t offset, std::span<const std::uint8_t> data);
  protocol::BootError Commit();
  void Abandon(protocol::BootError error);  // an update that cannot go on
  void Stay(protocol::StayReason reason);
  void Reply(protocol::BootRequest request, protocol::BootError error,
             std::uint8_t sequence);
  void SendStatus();
  void SendInfo();
  void Push(const protocol::CanFrame& frame);
  void Flush();

  BootloaderConfig config_;
  AppRegion region_;
  hal::CanPort* can_;
  volatile BootHandoff* handoff_;
  protocol::IsoTpReceiver isotp_;
  protocol::BootState state_ = protocol::BootState::kReady;
  protocol::StayReason reason_ = protocol::StayReason::kNone;
  protocol::BootError error_ = protocol::BootError::kNone;
  InstalledImage image_;
  // The update in progress.
  ImageHeader incoming_;
  HeaderBytes incoming_bytes_{};
  std::uint32_t next_offset_ = 0;   // image bytes programmed
  std::uint32_t erased_pages_ = 0;  // region pages erased since the Begin
  // Timers (board ms).
  std::uint32_t now_ms_ = 0;
  std::uint32_t window_start_ms_ = 0;
  std::uint32_t last_status_ms_ = 0;
  std::uint32_t last_info_ms_ = 0;
  bool status_due_ = false;
  bool reset_pending_ = false;
  std::uint32_t reset_at_ms_ = 0;
  // Frames waiting for the port.
  std::array<protocol::CanFrame, kOutboxFrames> outbox_{};
  std::size_t out_head_ = 0;
  std::size_t out_count_ = 0;
  std::uint32_t dropped_ = 0;
};

}  // namespace mjc::boot
