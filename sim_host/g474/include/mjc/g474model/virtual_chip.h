// The virtual STM32G474: the register models composed behind the address decoder the
// drivers' Read16/Read32/Write16/Write32 reach on the host (mjc::stm32g4::RegisterSpace),
// with virtual time, the Cortex-M4's interrupt entry, and the world's side of the
// board's wiring.
//
// Time: the chip counts CPU cycles at the SYSCLK the RCC model gives (16 MHz HSI16 after
// reset); every register access costs `access_cycles`, interrupt entry and exit 12 each
// (Cortex-M4 TRM, "exception entry latency"), so busy-wait loops on a ready flag end
// as on the chip. WaitForInterrupt() jumps to the next event of any model or of the
// world's schedule. World events (Schedule) run at their time, between accesses, with
// every model brought to it first. Between events the models are advanced lazily: an
// access brings the block it reaches (and what that block's state depends on) to the
// present, and every model is brought there when the earliest of their next events
// (NextEvent) comes — the same states as advancing all of them at every access,
// since a model catches up exact over any interval, at a fraction of the cost. The
// world reads the models' state from its events (or after AdvanceTo).
//
// Interrupts: a model's interrupt line high makes its IRQ pending in the NVIC; a
// pending, enabled IRQ is taken after the access in progress (or in WFI) when PRIMASK
// is clear and its group priority (NVIC_IPR, lower wins, AIRCR.PRIGROUP) is strictly
// higher than the running handler's — preemption, and no re-entry at the same level.
// The handler is the function registered for that IRQ (the same function the image's
// vector table holds); lines are level-sensitive, so a handler that does not clear its
// flag is entered again.
//
// The NMI: a read of the flash array that finds an ECC double error (Flash) raises it
// at once, whatever PRIMASK and the running handler's priority (ARMv7-M B1.5.2: NMI is
// priority -2 and cannot be masked); the NMI handler (SetNmiHandler, the image's
// vector 2) runs before the read returns, and the read then returns the data as read.
// With no NMI handler the chip does what both images' DefaultHandler did at vector 2:
// a system reset (reported as a violation) — on a board that reads such a double word
// at every start, a reset loop.
//
// Resets: IWDG expiry, AIRCR.SYSRESETREQ and a power cut (the world's PowerCut or a
// flash power cut scheduled with flash().CutPowerAfter) reset every model — the flash
// array keeps its contents, RCC_CSR gets the cause's flags — and then call the reset
// handler, which by default throws ChipReset so that the firmware's stack unwinds back
// to the owner, who starts the firmware again (its RAM is gone: the owner constructs
// it anew). Virtual time goes on across resets.
//
// Violations of the manual's rules by the code under test land in violations(); any
// access outside the modelled address map is one too ("bus").
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <random>

#include "hal/stm32g4/mmio.h"
#include "mjc/g474model/as5047p.h"
#include "mjc/g474model/common.h"
#include "mjc/g474model/cortex.h"
#include "mjc/g474model/dbgmcu.h"
#include "mjc/g474model/fdcan.h"
#include "mjc/g474model/flash.h"
#include "mjc/g474model/gpio.h"
#include "mjc/g474model/iwdg.h"
#include "mjc/g474model/rcc.h"
#include "mjc/g474model/spi.h"
#include "mjc/g474model/timer.h"

namespace mjc::g474model {

// IRQ numbers (RM0440 vector table; ST's SVD v2.9).
namespace irq {
inline constexpr int kFlash = 4, kRcc = 5, kFdcan1It0 = 21, kFdcan1It1 = 22, kTim1Up = 25,
                     kTim3 = 29, kSpi1 = 35;
}

enum class ResetCause : std::uint8_t { kSoftware, kIwdg, kPowerCut, kOptionLoad };
const char* ResetCauseName(ResetCause c);

// Thrown by the default reset handler (and caught by the owner).
struct ChipReset {
  ResetCause cause;
};
// Thrown when virtual time would pass the owner's limit (SetTimeLimit).
struct TimeLimitReached {
  Picoseconds at;
};

// What the board puts on PB8-BOOT0 (the world's side of the boot decision).
enum class Boot0Pin : std::uint8_t { kPulledDown, kPulledUp, kFloating };

struct ChipConfig {
  RccConfig rcc;
  FlashConfig flash;
  // The joint board's schematic has PB8 pulled down (docs/BRINGUP.md); a floating pin
  // reads a level drawn from `boot0_seed` at every reset.
  Boot0Pin boot0 = Boot0Pin::kPulledDown;
  std::uint64_t boot0_seed = 1;
  unsigned access_cycles = 4;  // per register access (AHB/APB bridge, a few cycles)
  unsigned exception_cycles = 12;
};

// Where the AS5047P hangs on the board.
struct SpiWiring {
  PinId sck = Pin('A', 5), miso = Pin('A', 6), mosi = Pin('A', 7), cs = Pin('A', 4);
};

// What the H-bridge sees: average drive in [-1, 1] (IN1 duty − IN2 duty) and the enable.
struct BridgeDrive {
  double duty = 0;
  bool enabled = false;
  bool floating = false;  // an input of the bridge is not driven by the chip
};

class VirtualChip final : public stm32g4::RegisterSpace {
 public:
  explicit VirtualChip(ChipConfig config = {});
  ~VirtualChip() override;
  VirtualChip(const VirtualChip&) = delete;
  VirtualChip& operator=(const VirtualChip&) = delete;

  // ── RegisterSpace ───────────────────────────────────────────────────────────────
  std::uint32_t Read(stm32g4::Address address, unsigned bytes) override;
  void Write(stm32g4::Address address, std::uint32_t value, unsigned bytes) override;
  void WaitForInterrupt() override;
  void MaskInterrupts(bool masked) override;

  // ── Time ────────────────────────────────────────────────────────────────────────
  Picoseconds now() const { return now_; }
  std::uint64_t cycles() const { return cycles_; }
  // CPU work between accesses (the firmware's own instructions), in cycles.
  void SpendCycles(std::uint64_t n);
  // Moves virtual time to `t` (≥ now), running due events and interrupts.
  void AdvanceTo(Picoseconds t);
  // Runs `fn` at virtual time `at` (between accesses or during WFI).
  void Schedule(Picoseconds at, std::function<void()> fn);
  // Throws TimeLimitReached when time would pass `t` (kNever: no limit).
  void SetTimeLimit(Picoseconds t) { limit_ = t; }

  // ── Interrupts and resets ───────────────────────────────────────────────────────
  void SetHandler(int irq, std::function<void()> handler);
  // The NMI handler (null: none, the default handler resets).
  void SetNmiHandler(std::function<void()> handler) { nmi_handler_ = std::move(handler); }
  int nmis() const { return nmis_; }
  bool primask() const { return primask_; }
  void SetResetHandler(std::function<void(ResetCause)> handler) {
    reset_handler_ = std::move(handler);
  }
  // The supply fails (a flash operation in progress is left as a cut leaves it) and
  // comes back: a power-on reset.
  void PowerCut();
  int resets() const { return resets_; }
  // Where the last reset (or the first power-on) booted, from the loaded option bytes
  // and PB8 (option_bytes.h, RM0440 §2.6). Anything but main flash runs no image of
  // ours: the owner calls RunWithoutImage instead of starting the firmware.
  BootSource boot_source() const { return boot_; }
  // The code the chip booted is not ours (ST's ROM bootloader, which has no FDCAN on
  // the G47x, or SRAM): the chip runs the world's events until a reset (which reaches
  // the reset handler as any other) or the time limit; returns at once when nothing
  // is left to happen.
  void RunWithoutImage();
  // The board's PB8 from now on (sampled at the next reset).
  void SetBoot0Pin(Boot0Pin pin);

  // ── A debugger ──────────────────────────────────────────────────────────────────
  // The core halted (DHCSR.C_HALT) and running again: while halted no interrupt is
  // taken and the firmware runs no code (the owner moves time on with AdvanceTo), and
  // each peripheral does what its DBGMCU freeze bit says (dbgmcu.h): the IWDG counts
  // on and resets the chip without DBG_IWDG_STOP, TIM1 goes on driving its outputs at
  // the last compare values without DBG_TIM1_STOP, with it the counter stops and the
  // outputs take their MOE-cleared levels; TIM3 counts on without DBG_TIM3_STOP. A
  // reset ends the halt (the debugger's reset vector catch is not modelled).
  void Halt();
  void Resume();
  bool halted() const { return halted_; }

  // ── The world's side ────────────────────────────────────────────────────────────
  // The motor's quadrature encoder: channels A and B on these pins.
  void AttachEncoder(PinId a, PinId b);
  // Moves the encoder to `position` (x4 counts), one quadrature edge at a time.
  void MoveEncoder(std::int64_t position);
  std::int64_t encoder_position() const { return encoder_pos_; }
  // The AS5047P on SPI1 with this wiring (owned by the chip).
  As5047p& AttachAs5047p(SpiWiring wiring = {});
  // The CAN transceiver's TXD/RXD pins (FDCAN1_TX/RX must be routed there).
  void AttachCanTransceiver(PinId tx, PinId rx);
  // A frame from the bus reaches FDCAN1 now (false: the controller was not listening).
  bool DeliverCanFrame(const CanBusFrame& frame);
  // What a pin drives over a PWM period.
  OutputWave PinWave(PinId p) const;
  BridgeDrive HBridge(PinId in1, PinId in2, PinId enable) const;

  // ── Models ──────────────────────────────────────────────────────────────────────
  Rcc& rcc() { return rcc_; }
  Pwr& pwr() { return pwr_; }
  Flash& flash() { return flash_; }
  GpioPort& gpio(char port) { return *gpio_[static_cast<std::size_t>(port - 'A')]; }
  const PinMux& pinmux() const { return mux_; }
  Timer& tim1() { return tim1_; }
  Timer& tim3() { return tim3_; }
  Spi& spi1() { return spi1_; }
  Fdcan& fdcan1() { return fdcan1_; }
  Iwdg& iwdg() { return iwdg_; }
  Cortex& cortex() { return cortex_; }
  Dbgmcu& dbgmcu() { return dbgmcu_; }
  ViolationLog& violations() { return log_; }

 private:
  struct Route {
    Peripheral* model;
    std::uint32_t offset;
    std::optional<Gate> gate;
    int kind;  // 0 registers, 1 flash array, 2 FDCAN RAM, 3 FDCAN config
  };
  std::optional<Route> Decode(std::uint32_t address);
  void Sync(Picoseconds t);
  void AdvanceModels(Picoseconds t);
  void AdvanceAll();
  void AdvanceDue();
  unsigned LinesOf(const Peripheral* m) const;
  // Laziness (see AdvanceAll): the models with timed events, each one's next event, and
  // the earliest of them, at which every model is brought to the present.
  static constexpr std::size_t kTimedModels = 8;
  Peripheral* Timed(std::size_t i);
  void UpdateDeadline();
  void Note(Peripheral* model);
  void Bring(const Route& route);
  void Settle(const Route& route);
  bool OutputOnly(const Route& route) const;  // a GPIO port's ODR, BSRR or BRR
  // The block behind an RCC enable/reset bit (null for the flash interface, which has
  // no reset bit).
  Peripheral* GatedBlock(Gate g);
  void UpdateGates();
  // Takes what the NVIC would take now; `sample`: the peripherals' lines are read
  // again even when no access since the last reading could have moved one.
  void ServiceInterrupts(bool sample = true);
  bool LineHigh(int irq) const;
  int CurrentPriority() const;
  void DoReset(ResetCause cause);
  // The boot decision at reset release.
  void SampleBoot();
  void OnPinLevel(PinId p, bool level);
  Drive AfDrive(PinId p) const;
  void CheckClocks() { rules_.Check(now_, flash_.latency()); }

  ChipConfig config_;
  ViolationLog log_;
  Picoseconds now_ = 0;
  std::uint64_t cycles_ = 0;
  unsigned __int128 cycle_remainder_ = 0;
  Picoseconds limit_ = kNever;
  std::array<Picoseconds, kTimedModels> next_{};
  Picoseconds deadline_ = 0;
  // Interrupt lines (a bit each, in the order of the IRQs the chip samples) that an
  // access or event may have moved since they were last sampled.
  static constexpr unsigned kAllLines = 0x3Fu;
  unsigned lines_dirty_ = kAllLines;
  // SpendCycles' last step: n cycles at f Hz are step_ps_ ps and step_rest_ / f ps.
  std::uint64_t step_cycles_ = 0, step_hz_ = 0, step_rest_ = 0;
  Picoseconds step_ps_ = 0;
  Rcc rcc_;
  Pwr pwr_;
  ClockRules rules_;
  Flash flash_;
  std::array<std::unique_ptr<GpioPort>, 7> gpio_;
  PinMux mux_;
  Timer tim1_, tim3_;
  Spi spi1_;
  Fdcan fdcan1_;
  Iwdg iwdg_;
  Cortex cortex_;
  Dbgmcu dbgmcu_;
  bool halted_ = false;
  void ApplyDebugFreeze();
  void ReportMpuFault(std::uint32_t address, bool write, int region);
  std::unique_ptr<As5047p> as5047p_;
  SpiWiring spi_wiring_;
  std::optional<PinId> enc_a_, enc_b_, can_tx_, can_rx_;
  std::int64_t encoder_pos_ = 0;
  std::multimap<Picoseconds, std::function<void()>> events_;
  std::map<int, std::function<void()>> handlers_;
  std::vector<int> active_stack_;
  bool primask_ = false;
  int resets_ = 0;
  BootSource boot_ = BootSource::kMainFlash;
  std::mt19937_64 boot0_rng_;
  std::optional<ResetCause> reset_pending_;
  std::function<void(ResetCause)> reset_handler_;
  std::function<void()> nmi_handler_;
  bool in_nmi_ = false;
  int nmis_ = 0;
  // Takes the NMI a flash read raised, if one did.
  void TakeFlashNmi();
};

}  // namespace mjc::g474model
