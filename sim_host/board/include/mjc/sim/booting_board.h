// A simulated joint board from its reset on, as the STM32G474 runs: first its CAN
// bootloader — the real boot::Bootloader logic over the board's whole flash, with its
// handoff block — which checks the installed image, keeps the 200 ms hold window, and
// stays when no valid image is installed, when a host holds it, when the application
// asked for it or after three starts the application never confirmed; then, when the
// bootloader hands over, the application (the firmware's JointBoard on the plant, as
// SimBoard runs it).
//
// The host cannot execute the ARM image the flash holds. At the hand-over the board
// "runs" the host build of the application instead, and reports (BoardInfo) the build
// named in the installed image's header — on the chip both are the same commit, since
// the build packs its own identity into the header. So an update of a simulated board
// changes the build it reports and nothing it does.
//
// Resets: the application entering the bootloader (its hal::BootEntry, on a host's
// BootHold) and the bootloader's Boot (a host's, after an update) are software resets:
// the handoff block (RAM) survives them, the flash always; the plant (the physical
// joint) is not reset. The application confirms a healthy start after 2 s of its ticks,
// as the G474 image's main loop does. A power cut is the end of the object (of the
// process, for mjc sim); a new one starts from power-on with random RAM. While the
// bootloader runs the plant is not stepped: the bridge is off and the joint at rest.
//
// Board time: Tick() is 100 µs of it (the application's control tick and one plant
// step, or only the clock in the bootloader); Poll() is a pass of the main loop, which
// the owner runs once a millisecond of board time, as mjc sim does.
#pragma once

#include <cstdint>
#include <deque>
#include <memory>
#include <optional>
#include <span>
#include <string_view>
#include <vector>

#include "hal/boot_entry.h"
#include "hal/can_port.h"
#include "hal/flash.h"
#include "hal/sim/sim_joint_io.h"
#include "mjc/app/joint_board.h"
#include "mjc/boot/bootloader.h"
#include "mjc/boot/handoff.h"
#include "mjc/plant/plant.h"

namespace mjc::sim {

// The board's flash: the STM32G474's whole 512 KB as 256 pages of 2 KB, laid out as on
// the chip (boot::kG474Layout): the bootloader's 16 KB (erased here: the host runs the
// logic, not its image), the application region, the identity pages 252-253 and the
// calibration pages 254-255.
inline constexpr std::uint32_t kBoardFlashPages = 256;
inline constexpr std::uint32_t kCalibrationPageA = 254;
inline constexpr std::uint32_t kCalibrationPageB = 255;
// The joint board's image type and the hardware revision of a board without an
// identity record (BOOTLOADER.md).
inline constexpr std::uint16_t kJointBoardType = 1;
inline constexpr std::uint8_t kDefaultHardwareRevision = 1;

// An image file (header in front) the bootloader accepts as the joint board's: board
// type 1, hardware 1..1, linked at 0x0800_4200, a vector table whose stack pointer is the
// top of SRAM and whose reset handler lies inside the image. Its bytes are no program —
// a note naming `describe` — since the simulated board runs the host build of the
// application; the header names `commit`, `dirty`, `commit_time_unix` and `describe`,
// which is what the board then reports.
std::vector<std::uint8_t> StandInImage(std::uint32_t commit, bool dirty,
                                       std::uint64_t commit_time_unix,
                                       std::string_view describe);

// Writes an image file into the application region as a debug probe would (the pages it
// covers erased, then its double-words programmed). False on a flash error or a file
// larger than the region.
bool InstallImage(hal::Flash& flash, std::span<const std::uint8_t> file);

struct BootingBoardConfig {
  // The application's configuration. Its can.node is the board's node id only when the
  // identity pages hold no record; its identity.build, dirty, reset_cause and instance
  // are the board's to fill in; its calibration pages are 254-255.
  app::JointBoardConfig app;
  // What the bootloader's BoardInfo says of the bootloader itself.
  std::uint32_t bootloader_build = 0;
  bool bootloader_dirty = false;
  // The chip's unique id, folded to 16 bits: both images report it.
  std::uint16_t instance = 0;
  // The handoff block's RAM after power-on (random on the chip).
  std::uint64_t ram_seed = 0;
};

// What happened on the board, for its owner to tell (mjc sim prints them).
struct BoardEvent {
  enum class Kind : std::uint8_t {
    kReset = 1,        // a reset: `cause`
    kBootloader = 2,   // the bootloader's state changed, or its progress passed a tenth
    kApplication = 3,  // the bootloader handed over: `build`, `dirty`, `calibration`
    kEnterBootloader = 4,  // the application accepted a host's BootHold
  };
  Kind kind = Kind::kReset;
  protocol::ResetCause cause = protocol::ResetCause::kUnknown;
  protocol::BootState state = protocol::BootState::kReady;
  protocol::StayReason reason = protocol::StayReason::kNone;
  protocol::BootError error = protocol::BootError::kNone;
  std::uint16_t progress_permille = 0;
  std::uint32_t build = 0;
  bool dirty = false;
  std::uint8_t node = 0;
  std::optional<std::uint32_t> calibration;  // the restored record's sequence
};

class BootingBoard {
 public:
  // `port` and `flash` (kBoardFlashPages pages) must outlive the board. Powers on: the
  // bootloader starts at board time 0, reset cause power-on.
  BootingBoard(const plant::PlantParams& params, const BootingBoardConfig& config,
               hal::CanPort* port, hal::Flash* flash);
  ~BootingBoard();
  BootingBoard(const BootingBoard&) = delete;
  BootingBoard& operator=(const BootingBoard&) = delete;

  // 100 µs of board time.
  void Tick();
  // A pass of the main loop: the bootloader's or the application's, then what it asked
  // for (the hand-over, a reset).
  void Poll();
  // The reset line (or the button), between steps: RAM and flash kept, reset cause pin.
  void PinReset() { Reset(protocol::ResetCause::kPin, false); }

  bool in_application() const { return app_ != nullptr; }
  // The running application (null while the bootloader runs).
  app::JointBoard* application() { return app_.get(); }
  // The bootloader (null while the application runs).
  const boot::Bootloader* bootloader() const { return boot_ ? &*boot_ : nullptr; }
  // The node id it answers with: the identity record's, read at every reset.
  std::uint8_t node() const { return node_; }
  // Board time since the last reset.
  std::uint64_t ticks() const { return ticks_; }
  std::uint32_t clock_ms() const;
  double tick_period_s() const { return period_s_; }
  plant::Plant& plant() { return *plant_; }
  std::uint32_t resets() const { return resets_; }
  const boot::BootHandoff& handoff() const { return handoff_; }

  // The oldest event not taken yet; false when there is none.
  bool TakeEvent(BoardEvent* out);

 private:
  class Entry final : public hal::BootEntry {
   public:
    explicit Entry(BootingBoard* board) : board_(board) {}

   private:
    void DoEnterBootloader() override;
    BootingBoard* board_;
  };

  void Reset(protocol::ResetCause cause, bool software);
  void HandOver();
  // Notes the bootloader's state when it changed (or its progress passed a tenth).
  void NoteBootloader();

  BootingBoardConfig config_;
  std::uint32_t tick_hz_;
  double period_s_;
  hal::CanPort* port_;
  hal::Flash* flash_;
  std::unique_ptr<plant::Plant> plant_;
  std::unique_ptr<hal::SimJointIo> io_;
  Entry entry_{this};
  boot::BootHandoff handoff_{};
  std::optional<boot::Bootloader> boot_;
  std::unique_ptr<app::JointBoard> app_;
  protocol::ResetCause reset_cause_ = protocol::ResetCause::kPowerOn;
  std::uint8_t node_ = 1;
  std::uint8_t hardware_revision_ = kDefaultHardwareRevision;
  std::uint64_t ticks_ = 0;
  bool confirmed_ = false;
  bool reset_requested_ = false;
  std::uint32_t resets_ = 0;
  std::deque<BoardEvent> events_;
  std::optional<BoardEvent> last_boot_;  // the bootloader's state last noted
};

}  // namespace mjc::sim
