// The joint board: the firmware's composition root. It owns the application (JointApp
// and its control tick), the joint service (its main loop: mjc/service/joint_service.h),
// the CAN node (the transport) and the calibration store, wires them to the board's CAN
// port and flash, boots them and serves the main loop: port → node → service → node →
// port. The STM32G474 image,
// the simulated board (`mjc sim`, the test rigs, the paper's scenarios) and the kernel
// self-test all build the board from this class: the board loop is written once.
//
// Contexts: ISR_Tick in the control tick's interrupt; everything else in the main loop.
// Nothing allocates; the board is ~20 KB (the tick's delay lines), a static object on
// the chip.
#pragma once

#include <cstdint>
#include <optional>

#include "hal/boot_entry.h"
#include "hal/can_port.h"
#include "hal/flash.h"
#include "hal/joint_io.h"
#include "mjc/app/calibration_store.h"
#include "mjc/app/can_node.h"
#include "mjc/app/joint_app.h"
#include "mjc/service/joint_service.h"

namespace mjc::app {

struct JointBoardConfig {
  ControlConfig control;
  CanNodeConfig can;
  // The flash pages of the calibration's A/B records (used with a flash).
  std::uint32_t calibration_page_a = 0;
  std::uint32_t calibration_page_b = 1;
};

class JointBoard {
 public:
  // Frames taken from the port per Poll, at most: a saturated CAN FD bus brings ~2 a
  // 100 µs tick; a flood beyond what a bus can carry must not starve the main loop.
  static constexpr int kMostFramesPerPoll = 32;

  // `port`, `flash` and `boot` must outlive the board; each may be null (a board without
  // a bus: its frames are dropped; without flash: nothing persists; without a
  // bootloader: a host's BootHold is ignored).
  JointBoard(const JointBoardConfig& config, hal::CanPort* port, hal::Flash* flash,
             hal::BootEntry* boot = nullptr);

  // Start-up, in the main loop before the tick runs: hands the newest stored
  // calibration to the app (it takes effect at the first tick) and returns it; nullopt
  // leaves the board uncalibrated (trials refused). The board announces itself (its
  // BoardInfo) at the first Poll, with a calibration page it could not read named in
  // BoardInfo.flash_unreadable.
  std::optional<CalibrationStore::Loaded> Boot();

  // The control tick (interrupt context).
  template <hal::JointIo Io>
  void ISR_Tick(Io& io) {
    app_.ISR_Tick(io);
  }

  // One pass of the main loop: the port's bus-off reports and received frames in (the
  // node decodes them into the service's requests), the service's poll (verdicts,
  // events, window fits, timeouts, reported to the node), the node's poll (telemetry),
  // its frames out as far as the
  // port takes them (the rest wait, in order, for the next pass). Last, when a host's
  // BootHold was accepted, the board enters its bootloader (hal::BootEntry): on the chip
  // this pass does not return.
  void Poll();

  // A fault whose cause stays for the whole run (the board did not come up whole:
  // Fault::kBoardStartup): raised again at every Poll, so it latches at the first tick
  // and no clear is accepted. Main loop, before the tick starts.
  void HoldFault(Fault fault) { held_fault_ = fault; }

  JointApp& app() { return app_; }
  const JointApp& app() const { return app_; }
  // The CAN node, for rigs that hand it frames past the port (a flood, a fuzzer).
  CanNode& node() { return node_; }
  const CanNode& node() const { return node_; }
  service::JointService& service() { return service_; }
  const service::JointService& service() const { return service_; }

 private:
  JointApp app_;
  std::optional<CalibrationStore> store_;
  service::JointService service_;
  CanNode node_;
  hal::CanPort* port_;
  hal::BootEntry* boot_;
  protocol::CanFrame held_;  // a frame the port had no room for
  bool holding_ = false;
  Fault held_fault_ = Fault::kNone;
};

}  // namespace mjc::app
