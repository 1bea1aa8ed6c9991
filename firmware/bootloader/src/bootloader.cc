#include "mjc/boot/bootloader.h"

#include "mjc/protocol/codec.h"
#include "mjc/protocol/little_endian.h"

namespace mjc::boot {
namespace {

using protocol::BootError;
using protocol::BootRequest;
using protocol::BootState;
using protocol::Function;
using protocol::StayReason;

constexpr std::uint8_t Code(Function f) { return static_cast<std::uint8_t>(f); }

}  // namespace

Bootloader::Bootloader(const BootloaderConfig& config, hal::Flash* flash,
                       hal::CanPort* can, volatile BootHandoff* handoff)
    : config_(config),
      region_(flash, config.layout),
      can_(can),
      handoff_(handoff),
      isotp_(protocol::MakeId(Code(Function::kBootIsoTpFromBoard), config.node)) {}

BootAction Bootloader::Start(std::uint32_t now_ms, bool software_reset) {
  now_ms_ = now_ms;
  last_status_ms_ = last_info_ms_ = now_ms;
  // Taken (erased) whatever happens next: a request lasts exactly one reset.
  const bool requested = TakeStayRequest(*handoff_, software_reset);
  image_ = CheckInstalledImage(
      region_, TargetFor(config_.layout, config_.board_type, config_.hardware_revision),
      config_.service);
  if (image_.check != ImageCheck::kValid) {
    Stay(StayReason::kNoValidImage);
    error_ = ToBootError(image_.check);
  } else if (!config_.clock_ok) {
    Stay(StayReason::kNoClock);
  } else if (requested) {
    Stay(StayReason::kRequested);
  } else if (BootAttempts(*handoff_, image_.header.image_crc) >= kMaxBootAttempts) {
    Stay(StayReason::kBootLoop);
  } else if (config_.hold_window_ms == 0) {
    SetBootAttempts(*handoff_, image_.header.image_crc,
                    BootAttempts(*handoff_, image_.header.image_crc) + 1);
    return BootAction::kBoot;
  } else {
    state_ = BootState::kHoldWindow;
    reason_ = StayReason::kNone;
    window_start_ms_ = now_ms;
  }
  SendInfo();
  SendStatus();
  Flush();
  return BootAction::kNone;
}

BootAction Bootloader::Poll(std::uint32_t now_ms) {
  now_ms_ = now_ms;
  protocol::CanFrame frame;
  while (can_ != nullptr && can_->Receive(&frame)) HandleFrame(frame, now_ms);
  if (isotp_.Poll(now_ms) == protocol::IsoTpEvent::kTimeout) {
    Reply(state_ == BootState::kReceiving ? BootRequest::kChunk : BootRequest::kBegin,
          BootError::kTransfer, 0);
  }
  if (state_ == BootState::kHoldWindow &&
      now_ms - window_start_ms_ >= config_.hold_window_ms) {
    // No hold came: count this start, then hand over.
    SetBootAttempts(*handoff_, image_.header.image_crc,
                    BootAttempts(*handoff_, image_.header.image_crc) + 1);
    return BootAction::kBoot;
  }
  if (status_due_ || now_ms - last_status_ms_ >= kStatusPeriodMs) SendStatus();
  if (now_ms - last_info_ms_ >= kInfoPeriodMs) SendInfo();
  Flush();
  if (reset_pending_ && static_cast<std::int32_t>(now_ms - reset_at_ms_) >= 0 &&
      out_count_ == 0) {
    return BootAction::kReset;
  }
  return BootAction::kNone;
}

void Bootloader::HandleFrame(const protocol::CanFrame& frame, std::uint32_t now_ms) {
  if (frame.id > 0x7FFu || protocol::NodeOf(frame.id) != config_.node) return;
  const std::uint8_t function = protocol::FunctionOf(frame.id);
  if (function == Code(Function::kBootIsoTpToBoard)) {
    HandleIsoTp(frame, now_ms);
    return;
  }
  if (function == Code(Function::kBootHold)) {
    protocol::BootHold hold;
    if (protocol::Decode(frame, &hold) != protocol::DecodeError::kOk) return;
    if (hold.key != protocol::kBootHoldKey) {
      Reply(BootRequest::kHold, BootError::kBadRequest, 0);
      return;
    }
    if (state_ == BootState::kHoldWindow) Stay(StayReason::kHoldFrame);
    Reply(BootRequest::kHold, BootError::kNone, 0);
    return;
  }
  if (function != Code(Function::kBootCommand)) return;
  protocol::BootCommand command;
  if (protocol::Decode(frame, &command) != protocol::DecodeError::kOk) return;
  // The host's attention in the window is a hold.
  if (state_ == BootState::kHoldWindow) Stay(StayReason::kHoldFrame);
  switch (command.request) {
    case BootRequest::kCommit:
      Reply(BootRequest::kCommit, Commit(), command.sequence);
      return;
    case BootRequest::kBoot:
      if (state_ == BootState::kReceiving || image_.check != ImageCheck::kValid) {
        Reply(BootRequest::kBoot, BootError::kNothingToBoot, command.sequence);
        return;
      }
      // The host takes the responsibility: the image gets its attempts afresh.
      SetBootAttempts(*handoff_, image_.header.image_crc, 0);
      reset_pending_ = true;
      reset_at_ms_ = now_ms + kResetDelayMs;
      Reply(BootRequest::kBoot, BootError::kNone, command.sequence);
      return;
    case BootRequest::kAbort:
      if (state_ == BootState::kReceiving) {
        state_ = BootState::kReady;
        status_due_ = true;
      }
      Reply(BootRequest::kAbort, BootError::kNone, command.sequence);
      return;
    case BootRequest::kHold:
    case BootRequest::kBegin:
    case BootRequest::kChunk:
      break;
  }
  Reply(command.request, BootError::kBadRequest, command.sequence);
}

void Bootloader::HandleIsoTp(const protocol::CanFrame& frame, std::uint32_t now_ms) {
  protocol::CanFrame flow;
  const protocol::IsoTpEvent event = isotp_.Handle(frame, now_ms, &flow);
  if (flow.length != 0) Push(flow);
  if (event == protocol::IsoTpEvent::kNone) return;
  if (event == protocol::IsoTpEvent::kComplete) {
    HandleRequest(isotp_.payload());
    return;
  }
  Reply(state_ == BootState::kReceiving ? BootRequest::kChunk : BootRequest::kBegin,
        BootError::kTransfer, 0);
}

void Bootloader::HandleRequest(std::span<const std::uint8_t> request) {
  const BootRequest fallback =
      state_ == BootState::kReceiving ? BootRequest::kChunk : BootRequest::kBegin;
  if (request.size() < kRequestHeaderBytes) {
    Reply(fallback, BootError::kBadRequest, 0);
    return;
  }
  const std::uint8_t sequence = request[1];
  if (state_ == BootState::kHoldWindow) Stay(StayReason::kHoldFrame);
  if (request[0] == static_cast<std::uint8_t>(BootRequest::kBegin)) {
    if (request.size() != kBeginBytes) {
      Reply(BootRequest::kBegin, BootError::kBadRequest, sequence);
      return;
    }
    Reply(BootRequest::kBegin, Begin(request.subspan<kRequestHeaderBytes, kHeaderSize>()),
          sequence);
    return;
  }
  if (request[0] == static_cast<std::uint8_t>(BootRequest::kChunk)) {
    if (request.size() < kChunkDataOffset) {
      Reply(BootRequest::kChunk, BootError::kBadChunk, sequence);
      return;
    }
    const auto offset = static_cast<std::uint32_t>(protocol::GetLe(&request[4], 4));
    Reply(BootRequest::kChunk, Chunk(offset, request.subspan(kChunkDataOffset)),
          sequence);
    return;
  }
  Reply(fallback, BootError::kBadRequest, sequence);
}

BootError Bootloader::Begin(std::span<const std::uint8_t, kHeaderSize> header) {
  ImageHeader h;
  ImageCheck check = DecodeHeader(header, &h);
  if (check == ImageCheck::kValid) {
    check = CheckHeaderFor(
        h, TargetFor(config_.layout, config_.board_type, config_.hardware_revision));
  }
  // Refused before anything is erased: the installed image stays as it was.
  if (check != ImageCheck::kValid) return ToBootError(check);
  // The header's page first: from here until the commit no valid image is in flash,
  // whatever a power cut leaves.
  image_.check = ImageCheck::kNoImage;
  reason_ = StayReason::kUpdate;
  const BootError erased = region_.ErasePageAt(0);
  if (erased != BootError::kNone) {
    Abandon(erased);
    return erased;
  }
  incoming_ = h;
  std::copy(header.begin(), header.end(), incoming_bytes_.begin());
  next_offset_ = 0;
  erased_pages_ = 1;
  state_ = BootState::kReceiving;
  error_ = BootError::kNone;
  status_due_ = true;
  return BootError::kNone;
}

BootError Bootloader::Chunk(std::uint32_t offset, std::span<const std::uint8_t> data) {
  if (state_ != BootState::kReceiving) return BootError::kNotReceiving;
  if (data.empty() || data.size() % hal::Flash::kDoubleWord != 0) {
    return BootError::kBadChunk;
  }
  if (offset != next_offset_) return BootError::kUnexpectedOffset;
  if (data.size() > incoming_.length - offset) return BootError::kBadChunk;
  const std::uint32_t page_bytes = config_.layout.PageBytes();
  for (std::size_t i = 0; i < data.size(); i += hal::Flash::kDoubleWord) {
    const std::uint32_t at =
        static_cast<std::uint32_t>(kHeaderArea) + offset + static_cast<std::uint32_t>(i);
    // Each page is erased once, when the image first reaches it.
    while (erased_pages_ <= at / page_bytes) {
      const BootError erased = region_.ErasePageAt(erased_pages_ * page_bytes);
      if (erased != BootError::kNone) {
        Abandon(erased);
        return erased;
      }
      ++erased_pages_;
      if (config_.service != nullptr) config_.service();
    }
    const BootError programmed = region_.Program(at, protocol::GetLe(&data[i], 8));
    if (programmed != BootError::kNone) {
      Abandon(programmed);
      return programmed;
    }
  }
  next_offset_ += static_cast<std::uint32_t>(data.size());
  return BootError::kNone;
}

BootError Bootloader::Commit() {
  if (state_ == BootState::kCommitted) return BootError::kNone;
  if (state_ != BootState::kReceiving) return BootError::kNotReceiving;
  if (next_offset_ != incoming_.length) return BootError::kIncomplete;
  const auto image = static_cast<std::uint32_t>(kHeaderArea);
  // The image as it is in flash, not as it was sent.
  std::uint32_t crc = 0;
  if (!RegionCrc(region_, image, incoming_.length, config_.service, &crc)) {
    Abandon(BootError::kFlashError);
    return BootError::kFlashError;
  }
  if (crc != incoming_.image_crc) {
    Abandon(BootError::kImageCrc);
    return BootError::kImageCrc;
  }
  std::array<std::uint8_t, 8> vectors{};
  if (region_.Read(image, vectors) != BootError::kNone ||
      CheckVectors(static_cast<std::uint32_t>(protocol::GetLe(&vectors[0], 4)),
                   static_cast<std::uint32_t>(protocol::GetLe(&vectors[4], 4)), incoming_,
                   config_.layout) != ImageCheck::kValid) {
    Abandon(BootError::kBadVectors);
    return BootError::kBadVectors;
  }
  // The header, its last double-word (CRC + commit mark) last: the image becomes valid
  // in that one program operation.
  constexpr std::uint32_t kLast = header_offset::kHeaderCrc;
  for (std::uint32_t at = 0; at < kLast; at += 8) {
    const BootError e = region_.Program(at, protocol::GetLe(&incoming_bytes_[at], 8));
    if (e != BootError::kNone) {
      Abandon(e);
      return e;
    }
  }
  const BootError last =
      region_.Program(kLast, protocol::GetLe(&incoming_bytes_[kLast], 8));
  if (last != BootError::kNone) {
    Abandon(last);
    return last;
  }
  image_ = CheckInstalledImage(
      region_, TargetFor(config_.layout, config_.board_type, config_.hardware_revision),
      config_.service);
  if (image_.check != ImageCheck::kValid) {
    Abandon(ToBootError(image_.check));
    return ToBootError(image_.check);
  }
  state_ = BootState::kCommitted;
  error_ = BootError::kNone;
  status_due_ = true;
  return BootError::kNone;
}

void Bootloader::Abandon(BootError error) {
  state_ = BootState::kReady;
  reason_ = StayReason::kUpdate;
  error_ = error;
  status_due_ = true;
}

void Bootloader::Stay(StayReason reason) {
  state_ = BootState::kReady;
  reason_ = reason;
  status_due_ = true;
}

std::uint16_t Bootloader::progress_permille() const {
  if (state_ == BootState::kCommitted) return 1000;
  if (state_ != BootState::kReceiving || incoming_.length == 0) return 0;
  // 32-bit arithmetic (no 64-bit division in the image): offset × 1000 fits while the
  // region is below 4 MB (the G474's is 240 KB, the header check bounds the length).
  if (config_.layout.RegionBytes() > 0xFFFFFFFFu / 1000u) {
    return static_cast<std::uint16_t>(next_offset_ / (incoming_.length / 1000u + 1u));
  }
  return static_cast<std::uint16_t>(next_offset_ * 1000u / incoming_.length);
}

void Bootloader::Reply(BootRequest request, BootError error, std::uint8_t sequence) {
  if (error != BootError::kNone) {
    error_ = error;
    status_due_ = true;
  }
  protocol::BootResult result;
  result.request = request;
  result.error = error;
  result.sequence = sequence;
  result.next_offset = next_offset_;
  Push(protocol::Encode(result, config_.node));
}

void Bootloader::SendStatus() {
  protocol::BootStatus status;
  status.state = state_;
  status.reason = reason_;
  status.error = error_;
  status.progress_permille = progress_permille();
  status.tick_ms = now_ms_;
  Push(protocol::Encode(status, config_.node));
  last_status_ms_ = now_ms_;
  status_due_ = false;
}

void Bootloader::SendInfo() {
  protocol::BoardInfo info;
  info.build = config_.build;
  info.dirty = config_.dirty;
  info.image = protocol::ImageKind::kBootloader;
  info.reset_cause = config_.reset_cause;
  info.instance = config_.instance;
  Push(protocol::Encode(info, config_.node));
  if (config_.chip_info != nullptr) {
    Push(protocol::Encode(config_.chip_info(), config_.node));
  }
  last_info_ms_ = now_ms_;
}

void Bootloader::Push(const protocol::CanFrame& frame) {
  if (out_count_ == outbox_.size()) {
    ++dropped_;
    return;
  }
  outbox_[(out_head_ + out_count_) % outbox_.size()] = frame;
  ++out_count_;
}

void Bootloader::Flush() {
  while (out_count_ > 0 && can_ != nullptr && can_->Send(outbox_[out_head_])) {
    out_head_ = (out_head_ + 1) % outbox_.size();
    --out_count_;
  }
  if (can_ == nullptr) out_count_ = 0;
}

}  // namespace mjc::boot
