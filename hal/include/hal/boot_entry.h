// The way from the running application into the board's own bootloader, taken when a
// host sends the board a BootHold while it rests (firmware/bootloader/BOOTLOADER.md, "the
// application's side"). Rare and slow, so a small virtual interface, called from the
// main loop only.
//
// What EnterBootloader does is the platform's:
//  - the STM32G474 (firmware/boards/g474_joint/main.cc): the bridge stopped, the queued
//    answer given a millisecond to leave, the stay request written to the handoff block,
//    interrupts off, a system reset. It does not return.
//  - the simulated board (sim_host/board, sim::BootingBoard): the same stay request in
//    its handoff block and a software reset that its owner carries out before the next
//    step. It returns; the caller must leave the board alone until then.
#pragma once

namespace mjc::hal {

class BootEntry {
 public:
  virtual ~BootEntry() = default;

  // Leaves the application for the bootloader, which then stays (StayReason kRequested)
  // and takes an image. The caller has checked that no motion runs.
  void EnterBootloader() { DoEnterBootloader(); }

 private:
  virtual void DoEnterBootloader() = 0;
};

}  // namespace mjc::hal
