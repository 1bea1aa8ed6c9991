// What the bootloader and the application tell each other across a reset: 32 bytes of
// RAM that neither image's start-up code initialises (the linker scripts' HANDOFF
// region, __boot_handoff: 0x2001_3FE0 on the G474, at the top of SRAM1, which no reset
// erases). Header-only: the application includes it to ask for the bootloader and to
// confirm a healthy start.
//
// RAM is random after power-on and keeps whatever was last written across every other
// reset, so each record carries a magic and a CRC-32 over its words: a random pattern
// passes both with probability 2^-64. On top of that:
//
//  - the stay request counts only after a software reset (RCC_CSR.SFTRSTF, which a
//    power-on clears), is read and erased by the bootloader at every reset, whatever
//    the cause — so it lasts exactly one reset, and no stale request from before can
//    count;
//  - the boot attempts name the image they count (its CRC-32), so a count left by an
//    earlier image never holds back a new one.
//
// The application's duties (firmware/bootloader/BOOTLOADER.md, "the application's
// side"): RequestBootloader() right before it requests a system reset (bridge off,
// interrupts off); ConfirmHealthyBoot() once it has run healthily (its tick and main
// loop and the CAN port, 2 s after its start).
#pragma once

#include <array>
#include <cstdint>

#include "mjc/protocol/crc32.h"

namespace mjc::boot {

struct BootHandoff {
  // The application → the bootloader: stay after this reset.
  std::uint32_t stay_magic;
  std::uint32_t stay_reason;  // StayRequestReason
  std::uint32_t stay_crc;     // CRC-32 of stay_magic, stay_reason (little-endian)
  std::uint32_t reserved;
  // The bootloader ↔ the application: starts of an image since it last confirmed.
  std::uint32_t attempts_magic;
  std::uint32_t attempts_image_crc;  // the image counted (its header's CRC-32)
  std::uint32_t attempts;            // hand-overs since its last confirmation
  std::uint32_t attempts_crc;        // CRC-32 of the three words above
};
static_assert(sizeof(BootHandoff) == 32, "the linker scripts' HANDOFF region");

inline constexpr std::uint32_t kStayMagic = 0x59415453u;      // "STAY"
inline constexpr std::uint32_t kAttemptsMagic = 0x544F4F42u;  // "BOOT"

// Why the application asks (travels to nobody: the bootloader reports kRequested).
enum class StayRequestReason : std::uint32_t {
  kHost = 1,  // a host sent BootHold to the running application
};

namespace handoff_detail {
inline std::uint32_t CrcOfWords(std::initializer_list<std::uint32_t> words) {
  std::uint32_t state = protocol::kCrc32Init;
  for (const std::uint32_t w : words) {
    const std::array<std::uint8_t, 4> b = {
        static_cast<std::uint8_t>(w), static_cast<std::uint8_t>(w >> 8),
        static_cast<std::uint8_t>(w >> 16), static_cast<std::uint8_t>(w >> 24)};
    state = protocol::Crc32Update(state, b);
  }
  return protocol::Crc32Final(state);
}
}  // namespace handoff_detail

// The application, right before its software reset.
inline void RequestBootloader(volatile BootHandoff& h,
                              StayRequestReason reason = StayRequestReason::kHost) {
  const auto r = static_cast<std::uint32_t>(reason);
  h.stay_magic = kStayMagic;
  h.stay_reason = r;
  h.stay_crc = handoff_detail::CrcOfWords({kStayMagic, r});
}

// The bootloader, at every reset: whether a valid request is there, and it is erased.
// `software_reset`: the reset came from a software request (RCC_CSR.SFTRSTF on the
// G474); any other reset ignores a request that checks out.
inline bool TakeStayRequest(volatile BootHandoff& h, bool software_reset) {
  const std::uint32_t magic = h.stay_magic, reason = h.stay_reason, crc = h.stay_crc;
  h.stay_magic = 0;
  h.stay_reason = 0;
  h.stay_crc = 0;
  return software_reset && magic == kStayMagic &&
         reason == static_cast<std::uint32_t>(StayRequestReason::kHost) &&
         crc == handoff_detail::CrcOfWords({magic, reason});
}

// Hand-overs to the image with CRC `image_crc` since it last confirmed; 0 when the
// record is not valid or counts another image.
inline std::uint32_t BootAttempts(const volatile BootHandoff& h,
                                  std::uint32_t image_crc) {
  const std::uint32_t magic = h.attempts_magic, crc_of_image = h.attempts_image_crc,
                      n = h.attempts, crc = h.attempts_crc;
  if (magic != kAttemptsMagic ||
      crc != handoff_detail::CrcOfWords({magic, crc_of_image, n}) ||
      crc_of_image != image_crc) {
    return 0;
  }
  return n;
}

inline void SetBootAttempts(volatile BootHandoff& h, std::uint32_t image_crc,
                            std::uint32_t attempts) {
  h.attempts_magic = kAttemptsMagic;
  h.attempts_image_crc = image_crc;
  h.attempts = attempts;
  h.attempts_crc = handoff_detail::CrcOfWords({kAttemptsMagic, image_crc, attempts});
}

// The application, once it runs healthily: its count starts again from 0.
inline void ConfirmHealthyBoot(volatile BootHandoff& h) {
  SetBootAttempts(h, h.attempts_image_crc, 0);
}

}  // namespace mjc::boot
