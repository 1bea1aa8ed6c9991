// IWDG of the STM32G474 (RM0440 "Independent watchdog (IWDG)"; offsets and reset values
// from ST's SVD v2.9): KR keys 0xCCCC (start; forces the LSI on), 0x5555 (unlock
// PR/RLR/WINR), 0xAAAA (reload), any other key relocks; PR/RLR/WINR written only while
// unlocked, each write shows SR.PVU/RVU/WVU for the update's duration (5 LSI cycles here;
// RM0440 gives "up to" a few LSI cycles); a 12-bit down-counter at f_LSI / (4·2^PR) (PR 6
// and 7 both /256); at the end of the count — (RL + 1) counter ticks after a reload, as
// RM0440's timeout table has it (RL = 0 gives one tick) — the watchdog asks for a reset.
// Window option: a reload while the counter is above WINR asks for a reset too.
//
// Under the debugger: with DBG_IWDG_STOP the counter stops while the core is halted
// (SetFrozen, from VirtualChip's Halt); without it the watchdog counts on and resets
// the chip at the end of its count, halted or not.
//
// Not covered: the hardware-watchdog option byte (IWDG_SW = 0 starting it at reset),
// freezing in Stop/Standby, the early-wakeup interrupt.
#pragma once

#include <cstdint>
#include <functional>

#include "mjc/g474model/common.h"
#include "mjc/g474model/rcc.h"
#include "mjc/g474model/register_table.h"

namespace mjc::g474model {

class Iwdg final : public Peripheral {
 public:
  static constexpr std::uint32_t kBase = 0x40003000;

  Iwdg(ViolationLog* log, Rcc* rcc) : log_(log), rcc_(rcc) { Reset(); }

  bool Read(const Access& a, std::uint32_t* value) override;
  bool Write(const Access& a) override;
  void Reset() override;
  void Advance(Picoseconds now) override;
  Picoseconds NextEvent() const override;

  // Called when the watchdog asks for a reset (the chip resets with IWDGRSTF).
  void SetExpiryHook(std::function<void()> hook) { expiry_hook_ = std::move(hook); }
  bool running() const { return running_; }
  // The core halted by a debugger with DBGMCU_APB1FZR1.DBG_IWDG_STOP set: the counter
  // stops where it is (and goes on from there). The caller advances the model to the
  // present first.
  void SetFrozen(bool frozen) { frozen_ = frozen; }
  std::uint32_t counter() const { return counter_; }

 private:
  // The registers without code of their own (register_table.h).
  static RegisterTable<Iwdg> Registers();
  std::uint32_t Divider() const;
  void Expire(const char* why);

  ViolationLog* log_;
  Rcc* rcc_;
  Picoseconds now_ = 0;
  TickCounter lsi_ticks_;
  std::uint32_t prescale_count_ = 0;  // LSI cycles into the present counter tick
  bool running_ = false;
  bool unlocked_ = false;
  bool frozen_ = false;
  std::uint32_t pr_ = 0, rlr_ = 0xFFF, winr_ = 0xFFF;
  std::uint32_t counter_ = 0xFFF;
  // Registers that are still being copied to the LSI domain, and until when.
  Picoseconds pvu_until_ = 0, rvu_until_ = 0, wvu_until_ = 0;
  std::function<void()> expiry_hook_;
};

}  // namespace mjc::g474model
