#include "mjc/host/firmware_update.h"

#include <algorithm>
#include <cinttypes>
#include <cstdio>
#include <filesystem>
#include <utility>

#include "hal/flash.h"
#include "image_file.h"
#include "mjc/boot/bootloader.h"
#include "mjc/boot/layout.h"
#include "mjc/host/describe.h"
#include "mjc/protocol/codec.h"
#include "mjc/protocol/crc32.h"
#include "mjc/protocol/little_endian.h"

namespace mjc::host {
namespace {

using namespace mjc::protocol;

constexpr auto kJointBoard = static_cast<std::uint16_t>(boot::BoardType::kG474Joint);
// After this much of its own time without entering its bootloader, the application is
// probably an image that does not know BootHold: the hint says what to do.
constexpr std::uint32_t kHintAfterMs = 2000;
// Board time the reset into the image may take: the bootloader's 20 ms before it
// resets, its check and 200 ms hold window, the application's start. Far more than that.
constexpr std::uint32_t kStartMs = 3000;
// Steps of a board's clock that count as its time passing: longer ones are a restart.
constexpr std::uint32_t kMostClockStepMs = 2000;

std::string Hex32(std::uint32_t v) {
  char out[16];
  std::snprintf(out, sizeof out, "0x%08" PRIX32, v);
  return out;
}

std::string BoardTypeName(std::uint16_t type) {
  switch (static_cast<boot::BoardType>(type)) {
    case boot::BoardType::kG474Joint:
      return "the joint board (board type 1)";
    case boot::BoardType::kQemuMps2An386:
      return "QEMU's mps2-an386 test board (board type 2)";
  }
  return "board type " + std::to_string(type);
}

std::string Percent(std::uint32_t part, std::uint32_t whole) {
  return std::to_string(
             whole == 0 ? 0 : static_cast<unsigned>(std::uint64_t{part} * 100 / whole)) +
         "%";
}

class KernelBootTransport final : public BootTransport {
 public:
  explicit KernelBootTransport(std::unique_ptr<IsoTpLink> link)
      : link_(std::move(link)) {}

 private:
  bool DoSend(std::span<const std::uint8_t> request, std::string* why) override {
    return link_->Send(request, why);
  }
  std::unique_ptr<IsoTpLink> link_;
};

}  // namespace

std::string FirmwareImage::BuildText() const {
  return BuildName(header.commit, header.dirty) + " (" + boot::DescribeOf(header) + ")";
}

std::optional<FirmwareImage> CheckFirmwareImage(std::vector<std::uint8_t> file,
                                                const std::string& name,
                                                std::string* why) {
  boot::ImageHeader h;
  const boot::ImageCheck check = boot::CheckImageFile(file, &h);
  const std::string size = std::to_string(file.size()) + " bytes";
  switch (check) {
    case boot::ImageCheck::kValid:
      break;
    case boot::ImageCheck::kNoImage:
      *why = name +
             ": not a firmware image (no MJCI header: the build writes "
             "maestro-jc-g474-app.bin, mjc-image pack makes one)";
      return std::nullopt;
    case boot::ImageCheck::kBadHeader:
      *why = name +
             ": damaged image header (its CRC, version or commit mark do not check out)";
      return std::nullopt;
    case boot::ImageCheck::kBadLength: {
      if (file.size() < boot::kHeaderArea) {
        *why = name + ": truncated: " + size + ", not even the " +
               std::to_string(boot::kHeaderArea) + "-byte header area";
      } else if (h.length % 8 != 0 || h.length < 8) {
        *why = name + ": its header gives an image length of " +
               std::to_string(h.length) + " bytes (not a whole number of double-words)";
      } else {
        const std::size_t want = boot::kHeaderArea + h.length;
        *why = name + (file.size() < want ? ": truncated: " : ": ") + size +
               ", its header says " + std::to_string(boot::kHeaderArea) + " + " +
               std::to_string(h.length) + " = " + std::to_string(want);
      }
      return std::nullopt;
    }
    case boot::ImageCheck::kImageCrc: {
      const std::uint32_t crc =
          protocol::Crc32(std::span<const std::uint8_t>(file).subspan(boot::kHeaderArea));
      *why = name + ": corrupted: the image's CRC-32 is " + Hex32(crc) +
             ", its header says " + Hex32(h.image_crc);
      return std::nullopt;
    }
    case boot::ImageCheck::kWrongBoard:
    case boot::ImageCheck::kWrongHardware:
    case boot::ImageCheck::kBadLoadAddress:
    case boot::ImageCheck::kBadVectors:
    case boot::ImageCheck::kUnreadable:  // a board's flash only, never a file's
      *why = name + ": " + boot::ImageCheckName(check);
      return std::nullopt;
  }
  const boot::BootLayout& layout = boot::kG474Layout;
  if (h.board_type != kJointBoard) {
    *why = name + ": built for " + BoardTypeName(h.board_type) + ", not " +
           BoardTypeName(kJointBoard);
    return std::nullopt;
  }
  if (h.load_address != layout.ImageAddress()) {
    *why = name + ": linked to run at " + Hex32(h.load_address) +
           ", not at the joint board's application address " +
           Hex32(layout.ImageAddress());
    return std::nullopt;
  }
  if (h.length > layout.MaxImageLength()) {
    *why = name + ": an image of " + std::to_string(h.length) +
           " bytes, more than the joint board's application region holds (" +
           std::to_string(layout.MaxImageLength()) + ")";
    return std::nullopt;
  }
  FirmwareImage out;
  out.name = name;
  out.file = std::move(file);
  out.header = h;
  return out;
}

std::optional<FirmwareImage> LoadFirmwareImage(const std::string& path,
                                               std::string* why) {
  std::error_code error;
  if (std::filesystem::is_directory(path, error)) {
    *why = path + ": is a folder, not an image file";
    return std::nullopt;
  }
  if (!std::filesystem::exists(path, error)) {
    *why = path + ": no such file";
    return std::nullopt;
  }
  std::vector<std::uint8_t> bytes;
  if (!boot::ReadFileBytes(path, &bytes)) {
    *why = path + ": cannot be read";
    return std::nullopt;
  }
  return CheckFirmwareImage(std::move(bytes), path, why);
}

std::unique_ptr<BootTransport> OpenKernelBootTransport(const std::string& iface,
                                                       std::uint8_t node,
                                                       std::string* why) {
  auto link = IsoTpLink::Open(
      iface, MakeId(static_cast<std::uint8_t>(Function::kBootIsoTpToBoard), node),
      MakeId(static_cast<std::uint8_t>(Function::kBootIsoTpFromBoard), node), why);
  if (!link) return nullptr;
  return std::make_unique<KernelBootTransport>(std::move(link));
}

FirmwareUpdate::FirmwareUpdate(CanLink* link, BootTransport* transport, std::uint8_t node,
                               const FirmwareImage& image, UpdateOptions options)
    : link_(link),
      transport_(transport),
      node_(node),
      image_(image),
      options_(std::move(options)) {}

std::uint8_t FirmwareUpdate::Expect(BootRequest request) {
  // Never 0: the bootloader answers a failed transfer with sequence 0.
  if (++sequence_ == 0) sequence_ = 1;
  awaited_request_ = request;
  awaited_sequence_ = sequence_;
  result_.reset();
  return sequence_;
}

bool FirmwareUpdate::Pump(int timeout_ms) {
  std::string why;
  ReceiveResult r = link_->Receive(timeout_ms, &why);
  for (; r; r = link_->Receive(0, &why)) Handle(r->frame);
  if (r.failed()) {
    link_failed_ = true;
    link_why_ = why;
    return false;
  }
  return true;
}

void FirmwareUpdate::Handle(const CanFrame& f) {
  if (NodeOf(f.id) != node_) return;
  const std::uint8_t function = FunctionOf(f.id);
  if (SentByBoard(function)) ++frames_;
  // A step of a clock, in ms, when it goes forwards by a plausible amount.
  const auto advance = [this](std::optional<std::uint32_t>& last, std::uint32_t now_ms) {
    if (last && now_ms >= *last && now_ms - *last <= kMostClockStepMs) {
      board_ms_ += now_ms - *last;
    }
    last = now_ms;
  };
  switch (static_cast<Function>(function)) {
    case Function::kBootStatus: {
      BootStatus s;
      if (Decode(f, &s) != DecodeError::kOk) return;
      // Its clock starts anew at every start of the bootloader.
      if (last_boot_ms_ && s.tick_ms < *last_boot_ms_) ++bootloader_starts_;
      advance(last_boot_ms_, s.tick_ms);
      last_app_ms_.reset();
      status_ = s;
      ++statuses_;
      in_bootloader_ = true;
      return;
    }
    case Function::kHeartbeat: {
      Heartbeat h;
      if (Decode(f, &h) != DecodeError::kOk) return;
      advance(last_app_ms_, h.tick / (kBoardTickHz / 1000u));
      last_boot_ms_.reset();
      ++heartbeats_;
      in_bootloader_ = false;
      status_.reset();  // the bootloader's last word no longer holds
      return;
    }
    case Function::kBoardInfo: {
      BoardInfo i;
      if (Decode(f, &i) != DecodeError::kOk) return;
      info_ = i;
      in_bootloader_ = i.image == ImageKind::kBootloader;
      if (!in_bootloader_) status_.reset();
      return;
    }
    case Function::kBootResult: {
      BootResult r;
      if (Decode(f, &r) != DecodeError::kOk || r.request != awaited_request_) return;
      // A failed transfer's answer carries no sequence: it counts unless the answer
      // itself came.
      const bool answer = r.sequence == awaited_sequence_ ||
                          awaited_request_ == BootRequest::kHold ||
                          (r.error == BootError::kTransfer && !result_);
      if (answer) result_ = r;
      return;
    }
    default:
      return;
  }
}

FirmwareUpdate::Wait FirmwareUpdate::Await(const std::function<bool()>& done,
                                           std::uint32_t board_ms,
                                           const std::function<bool()>& each) {
  const std::uint64_t start_ms = board_ms_;
  auto heard_at = options_.now();
  std::uint64_t frames_seen = frames_;
  for (;;) {
    if (done()) return Wait::kDone;
    if (options_.interrupt != nullptr && options_.interrupt->load()) {
      return Wait::kInterrupted;
    }
    if (each && !each()) return Wait::kBoardTime;
    if (link_failed_ || !Pump(each ? 5 : 20)) return Wait::kLinkFailed;
    if (done()) return Wait::kDone;
    const auto now = options_.now();
    if (frames_ != frames_seen) {
      frames_seen = frames_;
      heard_at = now;
    }
    if (board_ms != 0 && board_ms_ - start_ms > board_ms) return Wait::kBoardTime;
    if (now - heard_at > options_.silence) return Wait::kSilent;
  }
}

std::optional<BootResult> FirmwareUpdate::AwaitAnswer(std::uint32_t board_ms,
                                                      Wait* wait) {
  *wait = Await([this] { return result_.has_value(); }, board_ms);
  if (*wait != Wait::kDone) return std::nullopt;
  return result_;
}

void FirmwareUpdate::Report(UpdateProgress::Phase phase, std::uint32_t programmed) {
  if (!options_.progress) return;
  UpdateProgress p;
  p.phase = phase;
  p.programmed = programmed;
  p.total = image_.header.length;
  options_.progress(p);
}

std::string FirmwareUpdate::Who() const { return "node " + std::to_string(node_); }

std::string FirmwareUpdate::Where() const {
  if (in_bootloader_ && status_) {
    return "left in its bootloader (" + DescribeBootStatus(*status_) +
           "), which waits for an image: run mjc flash again";
  }
  if (frames_ == 0) return "never heard";
  return in_bootloader_ ? "left in its bootloader: run mjc flash again"
                        : "it runs its application";
}

FirmwareUpdate::Step FirmwareUpdate::FailWith(UpdateResult* r, const std::string& what) {
  r->end = UpdateEnd::kFailed;
  r->in_bootloader = in_bootloader_;
  r->message = what + "; " + Where();
  return Step::kEnd;
}

FirmwareUpdate::Step FirmwareUpdate::Fail(UpdateResult* r, Wait wait,
                                          const std::string& doing) {
  switch (wait) {
    case Wait::kLinkFailed:
      r->end = UpdateEnd::kLinkFailed;
      r->in_bootloader = in_bootloader_;
      r->message = link_why_ + " (" + doing + "); " + Who() + ": " + Where();
      return Step::kEnd;
    case Wait::kInterrupted:
      return FailWith(r, "interrupted " + doing);
    case Wait::kSilent: {
      if (committed_) return AwaitReturn(r, doing);
      const std::string progress =
          erased_ ? " (" + Percent(next_offset_, image_.header.length) + " programmed)"
                  : "";
      r->end = UpdateEnd::kFailed;
      r->in_bootloader = erased_;
      r->message =
          Who() + " went silent " + doing + progress +
          (erased_
               ? ": a power cut or a reset? Its image is not whole, so it comes up in "
                 "its bootloader, which waits for an image: run mjc flash again"
               : ": a power cut or a reset? Its image was not touched");
      return Step::kEnd;
    }
    case Wait::kBoardTime:
    case Wait::kDone:
      break;
  }
  return FailWith(r, Who() + " did not answer " + doing);
}

bool FirmwareUpdate::RunsApplication() const {
  return info_ && info_->image == ImageKind::kApplication;
}

bool FirmwareUpdate::StaysSince(std::uint64_t starts) const {
  return bootloader_starts_ != starts && status_ &&
         (status_->state == BootState::kReady || status_->state == BootState::kReceiving);
}

FirmwareUpdate::Step FirmwareUpdate::AwaitReturn(UpdateResult* r,
                                                 const std::string& doing) {
  // The image is whole and committed, so a board that lost power or was reset after
  // the commit starts it when it comes back (its bootloader checks it and hands over):
  // listen one more silence for its return, and report what it runs.
  const std::string gone = Who() + " went silent " + doing + " (a power cut or a reset?)";
  const auto started = [&] { return RunsApplication(); };
  const auto stayed = [&] { return StaysSince(starts_at_commit_); };
  const Wait w = Await([&] { return started() || stayed(); }, 0);
  if (w == Wait::kDone && started()) {
    if (info_->build == image_.header.commit && info_->dirty == image_.header.dirty) {
      r->end = UpdateEnd::kUpdated;
      r->in_bootloader = false;
      r->message = gone + " and came back running " + image_.BuildText() +
                   ": the committed image held";
      return Step::kEnd;
    }
    return FailWith(r, gone + " and came back running build " +
                           BuildName(info_->build, info_->dirty) + ", not the image's " +
                           image_.BuildText());
  }
  if (w == Wait::kDone) {
    r->end = UpdateEnd::kFailed;
    r->in_bootloader = true;
    r->message = gone + " and came back in its bootloader, which stays (" +
                 DescribeBootStatus(*status_) + "): run mjc flash again";
    return Step::kEnd;
  }
  if (w == Wait::kSilent) {
    r->end = UpdateEnd::kGoneCommitted;
    r->in_bootloader = false;
    r->message = gone +
                 " after the new image was committed, and has not come back: "
                 "the image is whole, and the board starts it when it is powered again "
                 "(mjc list shows what it runs)";
    return Step::kEnd;
  }
  return Fail(r, w, "while it came back");
}

FirmwareUpdate::Step FirmwareUpdate::Catch(UpdateResult* r) {
  Report(UpdateProgress::Phase::kCatching, 0);
  (void)Expect(BootRequest::kHold);
  const auto first = options_.now();
  auto next_hold = first;
  bool held = false;
  bool hinted = false;
  std::uint64_t held_at_ms = 0;
  const auto caught = [this] {
    return status_ && status_->state != BootState::kHoldWindow;
  };
  // Only a running application answers a hold so.
  const auto refused = [this] {
    return result_ && result_->error == BootError::kMotionRunning;
  };
  const auto holding = [&] {
    const auto now = options_.now();
    if (now >= next_hold) {
      std::string why;
      if (!link_->Send(Encode(BootHold{}, node_), &why)) {
        link_failed_ = true;
        link_why_ = why;
        return true;
      }
      // Keep the cadence when a turn ran late; start afresh after a pause.
      next_hold =
          now - next_hold < kHoldPeriod ? next_hold + kHoldPeriod : now + kHoldPeriod;
      if (!held) {
        held = true;
        held_at_ms = board_ms_;
        if (options_.after_first_hold) options_.after_first_hold();
      }
    }
    // A running application that keeps talking without entering its bootloader.
    if (held && !status_ && heartbeats_ > 0) {
      const std::uint64_t ms = board_ms_ - held_at_ms;
      if (ms > kHintAfterMs && !hinted) {
        hinted = true;
        if (options_.hint) {
          options_.hint(Who() + "'s application has not entered its bootloader after " +
                        std::to_string(kHintAfterMs / 1000) +
                        " s of its time: reset or power-cycle the board now (the holds "
                        "keep it in its bootloader as it starts)");
        }
      }
      if (ms > static_cast<std::uint64_t>(options_.enter_patience.count())) return false;
    }
    return true;
  };
  const Wait w = Await([&] { return caught() || refused(); }, 0, holding);
  switch (w) {
    case Wait::kDone:
      if (caught()) return Step::kNext;
      r->end = UpdateEnd::kMotionRunning;
      r->message = Who() +
                   " is running a motion (a trial, calibration sweep or stream): stop it "
                   "first (mjc stop --node " +
                   std::to_string(node_) + "); nothing was done";
      return Step::kEnd;
    case Wait::kBoardTime:
      r->end = UpdateEnd::kNotEntering;
      r->message =
          Who() +
          " runs its application, which did not enter its bootloader on a "
          "BootHold within " +
          std::to_string(options_.enter_patience.count() / 1000) +
          " s of its time (an image from before mjc flash?): run mjc flash again "
          "and reset or power-cycle the board while it waits; nothing was done";
      return Step::kEnd;
    case Wait::kSilent:
      if (frames_ == 0) {
        r->end = UpdateEnd::kSilent;
        r->message = SilentNode(node_, link_->Name()) + "; nothing was done";
        return Step::kEnd;
      }
      return FailWith(r, Who() + " went silent while it was being caught");
    case Wait::kInterrupted:
      if (!in_bootloader_) {
        r->end = UpdateEnd::kInterrupted;
        r->message = "interrupted before anything was done";
        return Step::kEnd;
      }
      return FailWith(r, "interrupted while catching " + Who());
    case Wait::kLinkFailed:
      return Fail(r, w, "while catching " + Who());
  }
  return Step::kEnd;
}

FirmwareUpdate::Step FirmwareUpdate::Begin(UpdateResult* r) {
  std::vector<std::uint8_t> request(boot::kBeginBytes, 0);
  request[0] = static_cast<std::uint8_t>(BootRequest::kBegin);
  std::copy(image_.header_bytes().begin(), image_.header_bytes().end(),
            request.begin() + boot::kRequestHeaderBytes);
  for (int failures = 0;;) {
    request[1] = Expect(BootRequest::kBegin);
    std::string why;
    Wait w = Wait::kDone;
    // Awaited even when the transport failed (no flow control): the board's clock and
    // its silence tell a lost transfer from a board that is gone.
    const bool sent = transport_->Send(request, &why);
    const auto answer = AwaitAnswer(kAnswerMs, &w);
    if (!answer && w != Wait::kBoardTime)
      return Fail(r, w, "while it took the image's header");
    if (answer && answer->error == BootError::kNone) {
      erased_ = true;
      next_offset_ = 0;
      Report(UpdateProgress::Phase::kUploading, 0);
      return Step::kNext;
    }
    if (answer && answer->error != BootError::kTransfer) {
      const auto code = static_cast<std::uint8_t>(answer->error);
      if (code >= 1 && code <= 8) {
        // Refused before anything was erased: its old image is as it was.
        StartOldImage(r,
                      std::string(BootErrorName(answer->error)) +
                          (answer->error == BootError::kWrongHardware
                               ? ": built for hardware revisions " +
                                     std::to_string(image_.header.hardware_min) + ".." +
                                     std::to_string(image_.header.hardware_max) +
                                     ", the board is another"
                               : ""));
        return Step::kEnd;
      }
      return FailWith(r, Who() + " refused the image's header (" +
                             std::string(BootErrorName(answer->error)) + ")");
    }
    if (++failures > kMostFailures) {
      return FailWith(r, Who() + " did not take the image's header in " +
                             std::to_string(kMostFailures + 1) + " tries" +
                             (sent ? "" : " (" + why + ")"));
    }
  }
}

FirmwareUpdate::Step FirmwareUpdate::Upload(UpdateResult* r) {
  const std::uint32_t length = image_.header.length;
  const auto image = image_.image();
  std::vector<std::uint8_t> request;
  int failures = 0, transfer_failures = 0;
  while (next_offset_ < length) {
    const std::uint32_t offset = next_offset_;
    const auto n = static_cast<std::uint32_t>(
        std::min<std::size_t>(boot::kMaxChunkData, length - offset));
    request.assign(boot::kChunkDataOffset, 0);
    request[0] = static_cast<std::uint8_t>(BootRequest::kChunk);
    request[1] = Expect(BootRequest::kChunk);
    PutLe(&request[4], offset, 4);
    request.insert(request.end(), image.begin() + offset, image.begin() + offset + n);
    std::string why;
    Wait w = Wait::kDone;
    const bool sent = transport_->Send(request, &why);
    const auto answer = AwaitAnswer(kAnswerMs, &w);
    if (!answer && w != Wait::kBoardTime) return Fail(r, w, "during the upload");
    const BootError error = answer ? answer->error : BootError::kTransfer;
    const bool plausible = answer && answer->next_offset <= length &&
                           answer->next_offset % hal::Flash::kDoubleWord == 0;
    if (answer && error == BootError::kNone && plausible) {
      next_offset_ = answer->next_offset;
      failures = 0;
      transfer_failures = 0;
      Report(UpdateProgress::Phase::kUploading, next_offset_);
      continue;
    }
    if (error == BootError::kUnexpectedOffset && plausible) {
      next_offset_ = answer->next_offset;  // the board says where it is: resume there
      if (++failures <= kMostFailures) continue;
    } else if (!sent && !answer) {  // the kernel's bound, the board alive (w above)
      ++r->chunks_resent;
      if (++transfer_failures <= kMostTransferFailures) continue;
      return FailWith(r, Who() + " did not take the chunk at offset " +
                             std::to_string(offset) + " in " +
                             std::to_string(kMostTransferFailures + 1) +
                             " transfers though it kept running (" + why + ")");
    } else if (error == BootError::kTransfer || (answer && !plausible)) {
      ++r->chunks_resent;
      if (++failures <= kMostFailures) continue;
    } else if (error == BootError::kFlashError || error == BootError::kNotReceiving) {
      // The board abandoned the update (or reset and lost it): begin again.
      last_restart_why_ = BootErrorName(error);
      return Step::kRestart;
    } else {
      return FailWith(r, Who() + " refused the chunk at offset " +
                             std::to_string(offset) + " (" +
                             std::string(BootErrorName(error)) + ")");
    }
    return FailWith(r, Who() + " did not take the chunk at offset " +
                           std::to_string(offset) + " in " +
                           std::to_string(kMostFailures + 1) + " tries" +
                           (sent ? "" : " (" + why + ")"));
  }
  return Step::kNext;
}

std::optional<BootResult> FirmwareUpdate::Command(BootRequest request,
                                                  std::uint32_t board_ms,
                                                  const std::string& doing,
                                                  UpdateResult* r, Step* end) {
  for (int failures = 0;;) {
    const std::uint8_t sequence = Expect(request);
    std::string why;
    if (!link_->Send(Encode(BootCommand{request, sequence}, node_), &why)) {
      link_failed_ = true;
      link_why_ = why;
      *end = Fail(r, Wait::kLinkFailed, "at " + doing);
      return std::nullopt;
    }
    Wait w = Wait::kDone;
    if (auto answer = AwaitAnswer(board_ms, &w)) return answer;
    if (w != Wait::kBoardTime) {
      *end = Fail(r, w, "at " + doing);
      return std::nullopt;
    }
    // Unanswered because the board restarted after the commit (a power cut or a reset
    // within the silence): what it runs now is the answer.
    if (committed_ && (bootloader_starts_ != starts_at_commit_ || RunsApplication())) {
      *end = AwaitReturn(r, "at " + doing);
      return std::nullopt;
    }
    if (++failures > kMostFailures) {
      *end = FailWith(r, Who() + " did not answer " + doing);
      return std::nullopt;
    }
  }
}

FirmwareUpdate::Step FirmwareUpdate::Commit(UpdateResult* r) {
  Report(UpdateProgress::Phase::kCommitting, next_offset_);
  for (;;) {
    Step end = Step::kEnd;
    const auto answer =
        Command(BootRequest::kCommit, kCommitAnswerMs, "the commit", r, &end);
    if (!answer) return end;
    switch (answer->error) {
      case BootError::kNone: {
        // The board's own CRC of the image in flash matched the header's (the file's,
        // checked here before the upload), and its header is written: committed.
        const Wait c =
            Await([this] { return status_ && status_->state == BootState::kCommitted; },
                  kAnswerMs);
        if (c == Wait::kDone) {
          committed_ = true;
          starts_at_commit_ = bootloader_starts_;
          return Step::kNext;
        }
        if (c != Wait::kBoardTime) return Fail(r, c, "after the commit");
        return FailWith(r, Who() +
                               " answered the commit but does not report the image "
                               "committed");
      }
      case BootError::kIncomplete: {
        next_offset_ = std::min(answer->next_offset, image_.header.length);
        const Step s = Upload(r);
        if (s != Step::kNext) return s;
        continue;
      }
      case BootError::kImageCrc:
      case BootError::kBadVectors:
      case BootError::kFlashError:
      case BootError::kUnreadable:
      case BootError::kNotReceiving:
        last_restart_why_ = BootErrorName(answer->error);
        return Step::kRestart;
      default:
        return FailWith(r, Who() + " refused the commit (" +
                               std::string(BootErrorName(answer->error)) + ")");
    }
  }
}

FirmwareUpdate::Step FirmwareUpdate::StartImage(UpdateResult* r, bool new_image) {
  Report(UpdateProgress::Phase::kBooting, next_offset_);
  Step end = Step::kEnd;
  const auto answer = Command(BootRequest::kBoot, kAnswerMs, "the boot", r, &end);
  if (!answer) return end;
  if (answer->error != BootError::kNone) {
    return FailWith(r, Who() + " refused to start " +
                           (new_image ? "the new image" : "its image") + " (" +
                           std::string(BootErrorName(answer->error)) + ")");
  }
  // It resets 20 ms later: its bootloader starts anew (a BoardInfo, then BootStatus in
  // the hold window, its clock from 0), then hands over, and the application sends its
  // BoardInfo. A BootStatus of that new start that says it stays ends the wait.
  const std::uint64_t starts = bootloader_starts_;
  info_.reset();
  const auto started = [&] { return RunsApplication(); };
  const auto stayed = [&] { return StaysSince(starts); };
  const Wait w = Await([&] { return started() || stayed(); }, kStartMs);
  if (w == Wait::kDone && started()) return Step::kNext;
  if (w == Wait::kDone) {
    return FailWith(r, Who() + " did not start " +
                           (new_image ? "the new image" : "its image") +
                           ": its bootloader stays");
  }
  if (w == Wait::kBoardTime) {
    return FailWith(r, Who() + " did not start " +
                           (new_image ? "the new image" : "its image") + " within " +
                           std::to_string(kStartMs) + " ms of its time");
  }
  return Fail(r, w, "while it started its image");
}

void FirmwareUpdate::StartOldImage(UpdateResult* r, const std::string& why) {
  if (StartImage(r, false) != Step::kNext) {
    r->message = Who() + " refused the image (" + why + "); " + r->message;
    return;
  }
  r->end = UpdateEnd::kRefused;
  r->in_bootloader = false;
  r->message = Who() + " refused the image (" + why +
               "): nothing was written, and it runs its old image again";
}

UpdateResult FirmwareUpdate::Run() {
  UpdateResult r;
  const auto started = options_.now();
  // What the node's images send that the update reads, and nothing else: on a raw
  // socket every frame of the image's own ISO-TP transfer would wake this process too
  // (a saving only: Handle checks the node itself).
  std::vector<IdFilter> filters;
  for (const Function f : {Function::kBootStatus, Function::kBootResult,
                           Function::kBoardInfo, Function::kHeartbeat}) {
    filters.push_back({MakeId(static_cast<std::uint8_t>(f), node_), 0x7FF});
  }
  std::string why;
  link_->SetFilters(filters, &why);
  const auto seconds = [](auto d) { return std::chrono::duration<double>(d).count(); };
  Step s = Catch(&r);
  while (s == Step::kNext) {
    const auto upload_start = options_.now();
    s = Begin(&r);
    if (s == Step::kNext) s = Upload(&r);
    if (s == Step::kNext) s = Commit(&r);
    if (s == Step::kRestart) {
      if (++r.restarts <= kMostRestarts) {
        s = Step::kNext;
        continue;
      }
      s = FailWith(&r, Who() + " abandoned the update " + std::to_string(r.restarts) +
                           " times (last: " + last_restart_why_ + ")");
      break;
    }
    if (s != Step::kNext) break;
    r.upload_s = seconds(options_.now() - upload_start);
    if (StartImage(&r, true) != Step::kNext) break;
    if (info_->build != image_.header.commit || info_->dirty != image_.header.dirty) {
      FailWith(&r, Who() + " started build " + BuildName(info_->build, info_->dirty) +
                       ", not the image's " + image_.BuildText());
      break;
    }
    r.end = UpdateEnd::kUpdated;
    r.in_bootloader = false;
    r.message = Who() + " runs " + image_.BuildText();
    break;
  }
  r.total_s = seconds(options_.now() - started);
  return r;
}

}  // namespace mjc::host
