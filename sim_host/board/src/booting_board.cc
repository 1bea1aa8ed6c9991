#include "mjc/sim/booting_board.h"

#include <algorithm>
#include <random>
#include <string>

#include "image_file.h"
#include "mjc/boot/app_region.h"
#include "mjc/boot/identity_store.h"
#include "mjc/boot/image_check.h"
#include "mjc/boot/layout.h"
#include "mjc/protocol/little_endian.h"

namespace mjc::sim {
namespace {

using boot::kG474Layout;

// The application confirms a healthy start after this much of its time, as the G474
// image's main loop does (firmware/boards/g474_joint/main.cc: 20,000 ticks).
constexpr std::uint32_t kConfirmAfterMs = 2000;

}  // namespace

std::vector<std::uint8_t> StandInImage(std::uint32_t commit, bool dirty,
                                       std::uint64_t commit_time_unix,
                                       std::string_view describe) {
  // A vector table (the stack's top in SRAM, a Thumb reset handler just behind the
  // table's two words), then a note; 1 KB in all.
  std::vector<std::uint8_t> image(1024, 0);
  protocol::PutLe(&image[0], kG474Layout.stack_ranges[0].end, 4);
  protocol::PutLe(&image[4], kG474Layout.ImageAddress() + 8u + 1u, 4);
  const std::string note = "maestro-jc host stand-in for " + std::string(describe) +
                           ": the simulated board runs the host build of the application";
  std::copy_n(note.begin(), std::min(note.size(), image.size() - 8), image.begin() + 8);
  boot::ImageHeader h;
  h.board_type = kJointBoardType;
  h.hardware_min = kDefaultHardwareRevision;
  h.hardware_max = kDefaultHardwareRevision;
  h.load_address = kG474Layout.ImageAddress();
  h.commit = commit;
  h.dirty = dirty;
  h.commit_time_unix = commit_time_unix;
  h.describe_cut = describe.size() > boot::kDescribeSize - 1;
  std::copy_n(describe.begin(), std::min(describe.size(), boot::kDescribeSize - 1),
              h.describe.begin());
  return boot::PackImage(image, h);
}

bool InstallImage(hal::Flash& flash, std::span<const std::uint8_t> file) {
  boot::AppRegion region(&flash, kG474Layout);
  if (file.size() > region.size() || file.size() % hal::Flash::kDoubleWord != 0) {
    return false;
  }
  const std::uint32_t page = kG474Layout.PageBytes();
  for (std::uint32_t at = 0; at < file.size(); at += page) {
    if (region.ErasePageAt(at) != protocol::BootError::kNone) return false;
  }
  for (std::uint32_t at = 0; at < file.size(); at += hal::Flash::kDoubleWord) {
    const std::uint64_t v = protocol::GetLe(&file[at], 8);
    if (v == ~std::uint64_t{0}) continue;  // erased already
    if (region.Program(at, v) != protocol::BootError::kNone) return false;
  }
  return true;
}

void BootingBoard::Entry::DoEnterBootloader() {
  boot::RequestBootloader(board_->handoff_);
  board_->reset_requested_ = true;
}

BootingBoard::BootingBoard(const plant::PlantParams& params,
                           const BootingBoardConfig& config, hal::CanPort* port,
                           hal::Flash* flash)
    : config_(config),
      tick_hz_(config.app.control.tick_hz),
      period_s_(1.0 / config.app.control.tick_hz),
      port_(port),
      flash_(flash),
      plant_(std::make_unique<plant::Plant>(params)),
      io_(std::make_unique<hal::SimJointIo>(plant_.get())) {
  // RAM after power-on: whatever the cells settle to.
  std::mt19937_64 rng(config.ram_seed);
  for (std::uint32_t* w :
       {&handoff_.stay_magic, &handoff_.stay_reason, &handoff_.stay_crc,
        &handoff_.reserved, &handoff_.attempts_magic, &handoff_.attempts_image_crc,
        &handoff_.attempts, &handoff_.attempts_crc}) {
    *w = static_cast<std::uint32_t>(rng());
  }
  Reset(protocol::ResetCause::kPowerOn, false);
}

BootingBoard::~BootingBoard() = default;

std::uint32_t BootingBoard::clock_ms() const {
  return static_cast<std::uint32_t>(ticks_ * 1000u / tick_hz_);
}

void BootingBoard::Tick() {
  ++ticks_;
  if (!app_) return;
  app_->ISR_Tick(*io_);
  plant_->Step(io_->duty(), io_->bridge_enabled(), period_s_);
}

void BootingBoard::Poll() {
  if (boot_) {
    const boot::BootAction action = boot_->Poll(clock_ms());
    NoteBootloader();
    if (action == boot::BootAction::kBoot) {
      HandOver();
    } else if (action == boot::BootAction::kReset) {
      Reset(protocol::ResetCause::kSoftware, true);
    }
    return;
  }
  app_->Poll();
  if (!confirmed_ && clock_ms() >= kConfirmAfterMs) {
    boot::ConfirmHealthyBoot(handoff_);
    confirmed_ = true;
  }
  if (reset_requested_) {
    BoardEvent e;
    e.kind = BoardEvent::Kind::kEnterBootloader;
    e.node = node_;
    events_.push_back(e);
    Reset(protocol::ResetCause::kSoftware, true);
  }
}

void BootingBoard::Reset(protocol::ResetCause cause, bool software) {
  app_.reset();
  boot_.reset();
  io_->ISR_Write(Actuation{});  // every pin back to input: the bridge is off
  ticks_ = 0;
  confirmed_ = false;
  reset_requested_ = false;
  reset_cause_ = cause;
  last_boot_.reset();
  ++resets_;
  BoardEvent e;
  e.kind = BoardEvent::Kind::kReset;
  e.cause = cause;
  events_.push_back(e);
  // The identity pages, read at every reset as the bootloader does.
  const auto identity = boot::IdentityStore(flash_, kG474Layout.identity_page_a,
                                            kG474Layout.identity_page_b)
                            .Load();
  node_ = identity ? identity->identity.node : config_.app.can.node;
  hardware_revision_ =
      identity ? identity->identity.hardware_revision : kDefaultHardwareRevision;
  boot::BootloaderConfig c;
  c.layout = kG474Layout;
  c.board_type = kJointBoardType;
  c.hardware_revision = hardware_revision_;
  c.node = node_;
  c.build = config_.bootloader_build;
  c.dirty = config_.bootloader_dirty;
  c.instance = config_.instance;
  c.reset_cause = cause;
  boot_.emplace(c, flash_, port_, &handoff_);
  const boot::BootAction action = boot_->Start(clock_ms(), software);
  NoteBootloader();
  if (action == boot::BootAction::kBoot) HandOver();
}

void BootingBoard::HandOver() {
  boot::AppRegion region(flash_, kG474Layout);
  const auto header = boot::ReadInstalledHeader(region);  // checked by the bootloader
  boot_.reset();
  app::JointBoardConfig c = config_.app;
  c.can.node = node_;
  c.can.identity.build = header ? header->commit : 0;
  c.can.identity.dirty = header ? header->dirty : false;
  c.can.identity.reset_cause = reset_cause_;
  c.can.identity.instance = config_.instance;
  c.calibration_page_a = kCalibrationPageA;
  c.calibration_page_b = kCalibrationPageB;
  app_ = std::make_unique<app::JointBoard>(c, port_, flash_, &entry_);
  const auto restored = app_->Boot();
  BoardEvent e;
  e.kind = BoardEvent::Kind::kApplication;
  e.build = c.can.identity.build;
  e.dirty = c.can.identity.dirty;
  e.node = node_;
  if (restored) e.calibration = restored->sequence;
  events_.push_back(e);
}

void BootingBoard::NoteBootloader() {
  if (!boot_) return;
  BoardEvent e;
  e.kind = BoardEvent::Kind::kBootloader;
  e.node = node_;
  e.state = boot_->state();
  e.reason = boot_->reason();
  e.error = boot_->error();
  e.progress_permille = boot_->progress_permille();
  if (e.state == protocol::BootState::kCommitted) {
    e.build = boot_->image().header.commit;
    e.dirty = boot_->image().header.dirty;
  }
  const bool changed = !last_boot_ || last_boot_->state != e.state ||
                       last_boot_->reason != e.reason || last_boot_->error != e.error ||
                       last_boot_->progress_permille / 100 != e.progress_permille / 100;
  if (!changed) return;
  last_boot_ = e;
  events_.push_back(e);
}

bool BootingBoard::TakeEvent(BoardEvent* out) {
  if (events_.empty()) return false;
  *out = events_.front();
  events_.pop_front();
  return true;
}

}  // namespace mjc::sim
