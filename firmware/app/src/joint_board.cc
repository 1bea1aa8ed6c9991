#include "mjc/app/joint_board.h"

namespace mjc::app {
namespace {

CanNodeConfig WithBootloader(CanNodeConfig config, bool bootloader) {
  config.bootloader = bootloader;
  return config;
}

}  // namespace

JointBoard::JointBoard(const JointBoardConfig& config, hal::CanPort* port,
                       hal::Flash* flash, hal::BootEntry* boot)
    : app_(config.control),
      store_(flash == nullptr ? std::nullopt
                              : std::optional<CalibrationStore>(
                                    std::in_place, flash, config.calibration_page_a,
                                    config.calibration_page_b)),
      service_(&app_, store_ ? &*store_ : nullptr),
      node_(&service_, WithBootloader(config.can, boot != nullptr)),
      port_(port),
      boot_(boot) {}

std::optional<CalibrationStore::Loaded> JointBoard::Boot() {
  if (!store_) return std::nullopt;
  auto restored = service_.Boot();
  // A calibration page the flash could not read (a save cut by a power loss): the
  // other page's record (or none) was taken; the board says so in its BoardInfo.
  const std::uint8_t bad = service_.unreadable_pages();
  node_.AddFlashUnreadable(static_cast<std::uint8_t>(
      ((bad & 1u) ? protocol::flash_unreadable::kCalibrationA : 0u) |
      ((bad & 2u) ? protocol::flash_unreadable::kCalibrationB : 0u)));
  return restored;
}

void JointBoard::Poll() {
  if (held_fault_ != Fault::kNone) app_.RaiseFault(held_fault_);
  if (port_ != nullptr) {
    for (std::uint32_t n = port_->TakeBusOff(); n > 0; --n) node_.OnBusOff();
    protocol::CanFrame frame;
    for (int i = 0; i < kMostFramesPerPoll && port_->Receive(&frame); ++i) {
      node_.HandleFrame(frame);
    }
  }
  // The service first (the tick's verdicts and events, as reports to the node), then the
  // node's own frames (telemetry).
  service_.Poll();
  node_.Poll();
  if (port_ == nullptr) {
    protocol::CanFrame dropped;
    while (node_.PopTx(&dropped)) {
    }
    return;
  }
  if (!holding_ || port_->Send(held_)) {
    holding_ = false;
    while (node_.PopTx(&held_)) {
      if (!port_->Send(held_)) {
        holding_ = true;
        break;
      }
    }
  }
  // The hold's answer is with the port (or waits behind a full one: it is a courtesy, the
  // host watches for the bootloader's own frames).
  if (boot_ != nullptr && service_.EnterBootloaderNow()) boot_->EnterBootloader();
}

}  // namespace mjc::app
