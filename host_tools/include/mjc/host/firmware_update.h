// A firmware update of one joint board over the bus, the host's side of the bootloader's
// protocol (firmware/bootloader/BOOTLOADER.md): the image file checked before anything
// is sent; the board caught (a running application asked into its bootloader, a board
// starting held in its hold window); the image sent in 248-byte chunks over ISO-TP, each
// acknowledged with the offset the board expects next; the commit, whose answer says
// that the board's own CRC of the image in flash matched the header's; the boot; and the
// application's BoardInfo with the new build. mjc flash runs one per board.
//
// Every wait is bounded by the board: by its clock (BootStatus.tick_ms while the
// bootloader runs, the heartbeat's tick while the application does) and by its silence
// (no frame at all from the node for Patience::silence), never by this machine's clock
// for progress. What the board answers decides what comes next: a lost or refused chunk
// is sent again from the offset the board names, a transfer that failed is repeated, an
// update the board had to abandon (a flash error, a CRC that did not match) begins
// again. Nothing outside the application region is ever written: the board's identity
// (node id) and calibration pages stay as they are, by the bootloader's construction.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "mjc/boot/image_header.h"
#include "mjc/host/board_client.h"
#include "mjc/host/can_link.h"
#include "mjc/protocol/messages.h"

namespace mjc::host {

// An image file checked for the joint board (STM32G474, board type 1): header,
// length and CRC as the packer wrote them, board type, load address and length against
// the board's application region. The hardware revision is the board's to check.
struct FirmwareImage {
  std::string name;                // the file, for messages
  std::vector<std::uint8_t> file;  // the header area, then the image
  boot::ImageHeader header;
  std::span<const std::uint8_t, boot::kHeaderSize> header_bytes() const {
    return std::span<const std::uint8_t>(file).first<boot::kHeaderSize>();
  }
  std::span<const std::uint8_t> image() const {
    return std::span<const std::uint8_t>(file).subspan(boot::kHeaderArea);
  }
  // "5eed1234 (v0.3-2-g5eed123)": the build the image carries.
  std::string BuildText() const;
};

// Reads and checks `path`. nullopt with a one-line reason naming the file: it cannot be
// read, it is not an image (no header), its header is damaged, it is truncated or
// padded, its CRC does not match (corrupted), or it is built for another board, address
// or a larger region.
std::optional<FirmwareImage> LoadFirmwareImage(const std::string& path, std::string* why);
// The same for bytes already read; `name` names them in messages.
std::optional<FirmwareImage> CheckFirmwareImage(std::vector<std::uint8_t> file,
                                                const std::string& name,
                                                std::string* why);

// The ISO-TP channel to one node's bootloader (requests on 0x3C << 4 | node, its flow
// control on 0x3D << 4 | node, classical frames: the bootloader's receiver takes no
// CAN FD ones).
class BootTransport {
 public:
  virtual ~BootTransport() = default;
  // Hands one request (1..256 bytes) to the transport: true once it is on its way;
  // false with the reason when this side could not send it, or the previous transfer
  // failed (the board gave no flow control in time).
  bool Send(std::span<const std::uint8_t> request, std::string* why) {
    return DoSend(request, why);
  }

 private:
  virtual bool DoSend(std::span<const std::uint8_t> request, std::string* why) = 0;
};

// The kernel's ISO-TP (CAN_ISOTP, IsoTpLink) on `iface` for `node`; nullptr with the
// reason when it cannot be opened (no can-isotp module).
std::unique_ptr<BootTransport> OpenKernelBootTransport(const std::string& iface,
                                                       std::uint8_t node,
                                                       std::string* why);

// How an update ended. mjc flash turns each into its exit status.
enum class UpdateEnd : std::uint8_t {
  kUpdated = 0,        // the board runs the new image and reports its build
  kMotionRunning = 1,  // the application runs a motion: refused, nothing done
  kSilent = 2,         // the node was never heard: nothing done
  kNotEntering = 3,    // the application talks but never entered its bootloader
  kRefused = 4,        // the bootloader refused the image before erasing anything; the
                       // old image was started again
  kFailed = 5,         // caught, but it does not run the new image (the message says
                       // where it was left: usually its bootloader, ready for another
                       // update)
  kLinkFailed = 6,     // this side could not send or receive
  kInterrupted = 7,    // a signal, before anything was done
  kGoneCommitted = 8,  // went silent after the image was committed and did not come
                       // back within a silence: the image is whole, and the board
                       // starts it when it is powered again (not seen running it)
};

struct UpdateProgress {
  enum class Phase : std::uint8_t { kCatching, kUploading, kCommitting, kBooting };
  Phase phase = Phase::kCatching;
  std::uint32_t programmed = 0;  // image bytes the board has programmed (its next_offset)
  std::uint32_t total = 0;       // the image's length
};

struct UpdateResult {
  UpdateEnd end = UpdateEnd::kFailed;
  // One line: what happened, and where the board was left when it was not updated.
  std::string message;
  // The board was last seen in its bootloader (kFailed: it waits there for an image).
  bool in_bootloader = false;
  // From the Begin to the commit's answer, and the whole update: the clock of
  // UpdateOptions::now (figures, never bounds).
  double upload_s = 0;
  double total_s = 0;
  int chunks_resent = 0;  // chunks sent again (a failed transfer, a lost answer)
  int restarts = 0;       // updates begun again (the board abandoned one)
};

struct UpdateOptions {
  // Silence (no frame at all from the node) that ends every wait.
  std::chrono::milliseconds silence = Patience{}.silence;
  // Board time a running application may take to enter its bootloader after the first
  // hold before the update gives up (it answers within a pass of its main loop; after
  // 2 s `hint` is called once: the board may run an image that does not know BootHold,
  // which a reset or power cycle while the holds go on catches in its hold window).
  std::chrono::milliseconds enter_patience{30000};
  // Called once the first BootHold is on the bus. This is where a reset line's pulse
  // goes (mjc flash --reset-line: gpio::PulseReset): holds sent from before the reset
  // catch the bootloader in its 200 ms hold window whatever the application does.
  std::function<void()> after_first_hold;
  // Once, when the application has not entered its bootloader after 2 s of its time.
  std::function<void(const std::string&)> hint;
  // At each phase and each acknowledged chunk.
  std::function<void(const UpdateProgress&)> progress;
  // A signal handler's flag: the update stops (kInterrupted before the board was caught;
  // kFailed, the board left in its bootloader, after).
  const std::atomic<bool>* interrupt = nullptr;
  // The clock of silence and of the figures (tests give a simulated one).
  BoardClient::Clock now = &std::chrono::steady_clock::now;
};

// One board's update. `link` (a raw link, filtered to the node by the update) and
// `transport` must outlive it.
class FirmwareUpdate {
 public:
  // The bootloader's answers, in its own time (BOOTLOADER.md: a Begin erases one page,
  // a chunk programs 31 double-words and sometimes erases a page, a commit reads the
  // whole image for its CRC); generous against the chip's figures (22-40 ms, 3 ms, 60
  // ms), since a lost answer only costs this wait.
  static constexpr std::uint32_t kAnswerMs = 500;
  static constexpr std::uint32_t kCommitAnswerMs = 1000;
  // The host's hold cadence: 20 holds in the 200 ms hold window, so Linux scheduling
  // delays of tens of ms and lost frames do not matter.
  static constexpr std::chrono::milliseconds kHoldPeriod{10};
  // Failures in a row (no answer, a failed transfer) before the update gives up on the
  // request; and updates begun again before it gives up on the board.
  static constexpr int kMostFailures = 5;
  static constexpr int kMostRestarts = 3;
  // Chunks whose transfer this host's kernel gave up on (no ISO-TP flow control within
  // its fixed 1 s of wall time) while the board kept its clock, in a row: a host too
  // busy for the kernel's bound (a board starved of CPU answers late), not a board that
  // refuses, so they have a budget of their own.
  static constexpr int kMostTransferFailures = 30;

  FirmwareUpdate(CanLink* link, BootTransport* transport, std::uint8_t node,
                 const FirmwareImage& image, UpdateOptions options = {});

  UpdateResult Run();

 private:
  enum class Wait : std::uint8_t {
    kDone,
    kBoardTime,
    kSilent,
    kLinkFailed,
    kInterrupted
  };
  enum class Step : std::uint8_t { kNext, kRestart, kEnd };

  // Handles what arrives within timeout_ms; false when the link failed.
  bool Pump(int timeout_ms);
  void Handle(const protocol::CanFrame& frame);
  // Until done() holds, the board's clock has run `board_ms` (0: no such bound) or it
  // is silent; `each` runs at every turn (the holds) and ends the wait (kBoardTime) by
  // returning false.
  Wait Await(const std::function<bool()>& done, std::uint32_t board_ms,
             const std::function<bool()>& each = {});
  // The next request's sequence (never 0), and the answer it awaits from now on.
  std::uint8_t Expect(protocol::BootRequest request);
  // The awaited answer (or a failed transfer's, which carries no sequence), within
  // `board_ms` of the board's time.
  std::optional<protocol::BootResult> AwaitAnswer(std::uint32_t board_ms, Wait* wait);

  // Sends BootCommand `request` until it is answered within `board_ms` (a lost command
  // or answer: again, at most kMostFailures more times); nullopt, with *end, when the
  // update ends there.
  std::optional<protocol::BootResult> Command(protocol::BootRequest request,
                                              std::uint32_t board_ms,
                                              const std::string& doing, UpdateResult* r,
                                              Step* end);
  Step Catch(UpdateResult* r);
  Step Begin(UpdateResult* r);
  Step Upload(UpdateResult* r);
  Step Commit(UpdateResult* r);
  // Boot: the reset, and the application's BoardInfo (kNext), or why not (kEnd).
  Step StartImage(UpdateResult* r, bool new_image);
  // The board refused the image before erasing: its old image is started again.
  void StartOldImage(UpdateResult* r, const std::string& why);
  // Ends the update after a wait that did not end well, or with `what`; the message
  // says where the board was left.
  Step Fail(UpdateResult* r, Wait wait, const std::string& doing);
  // Silent after the commit: waits a silence more for the board's return and reports
  // what it runs then (the new image, its bootloader, or nothing heard).
  Step AwaitReturn(UpdateResult* r, const std::string& doing);
  // The node's last BoardInfo is its application's.
  bool RunsApplication() const;
  // Its bootloader started anew since `starts` (bootloader_starts_ then) and stays.
  bool StaysSince(std::uint64_t starts) const;
  Step FailWith(UpdateResult* r, const std::string& what);
  std::string Who() const;
  std::string Where() const;
  void Report(UpdateProgress::Phase phase, std::uint32_t programmed);

  CanLink* link_;
  BootTransport* transport_;
  std::uint8_t node_;
  const FirmwareImage& image_;
  UpdateOptions options_;
  std::uint8_t sequence_ = 0;
  protocol::BootRequest awaited_request_ = protocol::BootRequest::kHold;
  std::uint8_t awaited_sequence_ = 0;
  // What the node sent.
  std::optional<protocol::BootStatus> status_;
  std::optional<protocol::BootResult> result_;
  std::optional<protocol::BoardInfo> info_;
  bool in_bootloader_ = false;           // which image spoke last
  std::uint64_t bootloader_starts_ = 0;  // its BootStatus clock went back to a new start
  std::uint64_t frames_ = 0;
  std::uint64_t statuses_ = 0;
  std::uint64_t heartbeats_ = 0;
  // The board's clock, in ms it has run while heard: the steps between consecutive
  // BootStatus (or heartbeat) clocks that go forwards by at most 2 s (a reset starts the
  // clock anew and adds nothing).
  std::uint64_t board_ms_ = 0;
  std::optional<std::uint32_t> last_boot_ms_;
  std::optional<std::uint32_t> last_app_ms_;
  bool link_failed_ = false;
  std::string link_why_;
  bool erased_ = false;                 // a Begin was accepted: the old image is gone
  bool committed_ = false;              // the board reported the new image committed
  std::uint64_t starts_at_commit_ = 0;  // bootloader_starts_ then
  std::uint32_t next_offset_ = 0;
  std::string last_restart_why_;
};

}  // namespace mjc::host
