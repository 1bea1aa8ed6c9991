// The Cortex-M4 system registers the firmware touches, from the ARMv7-M Architecture
// Reference Manual (DDI 0403E, chapter B3 "System Address Map": NVIC B3.4, SCB B3.2,
// DWT C1.8, debug DEMCR C1.6) and the Cortex-M4 TRM (4 priority bits on the STM32G4:
// __NVIC_PRIO_BITS = 4 in ST's CMSIS header; 102 external interrupts per RM0440's
// vector table).
//
// Covered: NVIC ISER/ICER/ISPR/ICPR/IABR/IPR and STIR; SCB CPUID, ICSR (VECTACTIVE,
// RETTOBASE not modelled), VTOR (alignment checked), AIRCR (VECTKEY, PRIGROUP,
// SYSRESETREQ → reset request), SCR, CCR, SHPR1-3, CPACR; DWT CTRL.CYCCNTENA and CYCCNT
// (counting virtual CPU cycles); CoreDebug DEMCR.TRCENA (DWT works only with it set).
// Interrupt scheduling itself (pending → active, preemption) lives in VirtualChip,
// which reads this model's state.
//
// MPU (B3.5): MPU_TYPE (8 regions), MPU_CTRL (ENABLE, HFNMIENA, PRIVDEFENA), MPU_RNR,
// MPU_RBAR (VALID selects the region) and MPU_RASR for each region; MpuDenies() checks
// an access against them as a privileged data access (all of this firmware runs
// privileged): the highest-numbered enabled region that holds the address decides
// (subregions disabled by SRD excluded), AP 000 denies everything, AP 101/110/111 deny
// writes, no region → the default map with PRIVDEFENA, a fault without; the private
// peripheral bus (0xE000_0000 - 0xE00F_FFFF) is never checked. The virtual chip checks
// only the accesses it sees — register and flash accesses, never RAM or instruction
// fetches (no instruction is executed) — and reports a denied one as a violation (the
// chip would take MemManage) without performing it. A size below 32 bytes or a base
// not aligned to the region's size (UNPREDICTABLE in the manual) is reported too.
//
// Not covered: SysTick, the RBAR/RASR alias registers, unprivileged execution
// (CONTROL.nPRIV), the MPU's effect on instruction fetches, stacking and HardFault/NMI
// handlers (HFNMIENA), FPU context control, fault status registers (reads 0),
// BASEPRI/FAULTMASK, ITM/TPIU.
#pragma once

#include <array>
#include <bitset>
#include <cstdint>
#include <functional>
#include <optional>

#include "mjc/g474model/common.h"
#include "mjc/g474model/register_table.h"

namespace mjc::g474model {

class Cortex final : public Peripheral {
 public:
  static constexpr std::uint32_t kBase = 0xE0000000;
  static constexpr std::uint32_t kDwtCyccnt = 0x1004;  // offset (ARMv7-M ARM C1.8.7)
  static constexpr int kIrqCount = 102;                // RM0440 vector table: IRQ 0..101

  Cortex(ViolationLog* log, const std::uint64_t* cpu_cycles)
      : log_(log), cycles_(cpu_cycles) {
    Reset();
  }

  bool Read(const Access& a, std::uint32_t* value) override;
  bool Write(const Access& a) override;
  void Reset() override;
  void Advance(Picoseconds now) override { now_ = now; }

  bool enabled(int irq) const { return enabled_[static_cast<std::size_t>(irq)]; }
  bool pending(int irq) const { return pending_[static_cast<std::size_t>(irq)]; }
  bool active(int irq) const { return active_[static_cast<std::size_t>(irq)]; }
  void SetPending(int irq, bool p) { pending_[static_cast<std::size_t>(irq)] = p; }
  void SetActive(int irq, bool a) { active_[static_cast<std::size_t>(irq)] = a; }
  // Some IRQ is pending and enabled but not active: a candidate for entry.
  bool AnyCandidate() const { return (pending_ & enabled_ & ~active_).any(); }
  // The IPR byte (only bits 7:4 implemented).
  std::uint8_t priority(int irq) const {
    return priority_[static_cast<std::size_t>(irq)];
  }
  // Group (preemption) priority of a priority byte under AIRCR.PRIGROUP.
  std::uint32_t GroupPriority(std::uint8_t priority) const {
    const unsigned prigroup = (aircr_ >> 8) & 7u;
    return priority & (0xFFu << (prigroup + 1)) & 0xFFu;
  }
  std::uint32_t vtor() const { return vtor_; }
  // DWT.CYCCNT is counting (DEMCR.TRCENA and DWT_CTRL.CYCCNTENA).
  bool cyccnt_running() const { return (demcr_ & (1u << 24)) && (dwt_ctrl_ & 1u); }
  // DWT_CYCCNT as a read returns it.
  std::uint32_t cyccnt() const { return Cyccnt(); }

  static constexpr int kMpuRegions = 8;  // Cortex-M4 with its MPU (TRM: 8 regions)
  // The MPU region that denies a privileged data access at `address` (`write`), -1 for
  // the background map without PRIVDEFENA; nullopt when the access is allowed.
  std::optional<int> MpuDenies(std::uint32_t address, bool write) const;
  bool mpu_enabled() const { return (mpu_ctrl_ & 1u) != 0; }

  // Called on AIRCR.SYSRESETREQ with the right VECTKEY.
  void SetResetRequestHook(std::function<void()> hook) { reset_hook_ = std::move(hook); }

 private:
  // The registers without code of their own (register_table.h).
  static RegisterTable<Cortex> Registers();
  std::uint32_t Cyccnt() const;

  ViolationLog* log_;
  const std::uint64_t* cycles_;
  Picoseconds now_ = 0;
  std::bitset<kIrqCount> enabled_, pending_, active_;
  std::array<std::uint8_t, kIrqCount> priority_{};
  std::uint32_t vtor_ = 0, aircr_ = 0, scr_ = 0, ccr_ = 0, cpacr_ = 0;
  std::array<std::uint32_t, 3> shpr_{};
  std::uint32_t dwt_ctrl_ = 0, demcr_ = 0;
  std::uint32_t mpu_ctrl_ = 0, mpu_rnr_ = 0;
  std::array<std::uint32_t, kMpuRegions> mpu_rbar_{}, mpu_rasr_{};
  // CYCCNT = (cycles - cycles at the last start or write) + value then, while running.
  std::uint32_t cyccnt_base_ = 0;
  std::uint64_t cyccnt_origin_ = 0;
  std::function<void()> reset_hook_;
};

}  // namespace mjc::g474model
