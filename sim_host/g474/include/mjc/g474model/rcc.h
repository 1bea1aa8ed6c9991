// RCC and PWR of the STM32G474, from RM0440 chapters "Reset and clock control (RCC)"
// and "Power control (PWR)" (register layout and reset values checked against ST's
// SVD v2.9, hal/stm32g4/svd/STM32G474.svd).
//
// Covered: the oscillators the firmware uses (HSI16, HSE, main PLL, LSI) with their
// ready flags appearing after start-up delays in virtual time; PLLCFGR with the "write
// only while the PLL is off" rule; CFGR SW → SWS (the switch happens once the selected
// source is ready) and the AHB/APB prescalers, from which SYSCLK, HCLK, PCLK1, PCLK2,
// the timer clocks (×2 when an APB prescaler is not 1) and the FDCAN kernel clock
// (CCIPR.FDCANSEL) follow; peripheral clock enables (a block whose clock is off reads
// 0 and ignores writes — the decoder asks ClockEnabled) and peripheral reset bits;
// CSR's reset-cause flags with RMVF. PWR: CR1.VOS, CR5.R1MODE (boost) and SR2.VOSF.
//
// Not covered (registers kept as plain storage): HSI48, LSE/RTC domain (BDCR), CSS,
// MCO, clock interrupts (CIER/CIFR), the sleep-mode enables, low-power modes.
//
// Start-up delays are the datasheet's (DS12288, "HSE/HSI16/PLL/LSI characteristics",
// from memory: tSU(HSE) ≈ 2 ms for a crystal, tLOCK ≤ 40 µs, tSU(LSI) ≤ 130 µs,
// tSU(HSI16) ≈ 1 µs); they are configurable because they depend on the board.
#pragma once

#include <array>
#include <cstdint>
#include <functional>

#include "mjc/g474model/common.h"
#include "mjc/g474model/register_table.h"

namespace mjc::g474model {

// Peripheral clocks the models depend on (each one an enable bit in RCC).
enum class Gate : std::uint8_t {
  kFlash,  // AHB1ENR.FLASHEN (bit 8, on after reset)
  kGpioA,
  kGpioB,
  kGpioC,
  kGpioD,
  kGpioE,
  kGpioF,
  kGpioG,  // AHB2ENR bits 0..6
  kTim3,   // APB1ENR1.TIM3EN (bit 1)
  kFdcan,  // APB1ENR1.FDCANEN (bit 25)
  kPwr,    // APB1ENR1.PWREN (bit 28)
  kTim1,   // APB2ENR.TIM1EN (bit 11)
  kSpi1,   // APB2ENR.SPI1EN (bit 12)
  kCount
};

struct RccConfig {
  double hse_hz = 8e6;  // the board's crystal; 0 = none fitted (HSERDY never sets)
  Picoseconds hse_startup = Microseconds(2000);
  Picoseconds pll_lock = Microseconds(40);
  Picoseconds hsi_startup = Microseconds(1);
  Picoseconds lsi_startup = Microseconds(130);
  double lsi_hz = 32000;  // LSI nominal (DS12288: 29.5–34 kHz over temperature)
};

// Reset-cause bits of RCC_CSR (RM0440 RCC_CSR; SVD v2.9).
namespace csr {
inline constexpr std::uint32_t kLsion = 1u << 0, kLsirdy = 1u << 1, kRmvf = 1u << 23;
inline constexpr std::uint32_t kOblrstf = 1u << 25, kPinrstf = 1u << 26,
                               kBorrstf = 1u << 27, kSftrstf = 1u << 28,
                               kIwdgrstf = 1u << 29, kWwdgrstf = 1u << 30,
                               kLpwrrstf = 1u << 31;
inline constexpr std::uint32_t kResetFlags = 0xFE000000u;
}  // namespace csr

class Pwr;

class Rcc final : public Peripheral {
 public:
  static constexpr std::uint32_t kBase = 0x40021000;

  Rcc(ViolationLog* log, const RccConfig& config);

  bool Read(const Access& a, std::uint32_t* value) override;
  bool Write(const Access& a) override;
  // A system reset: every register to its reset value except CSR's reset flags, which
  // only RMVF (or a power-on) clears. The flag of the cause is set by the chip.
  void Reset() override;
  void Advance(Picoseconds now) override;
  Picoseconds NextEvent() const override;

  // Power-on: CSR's flags become BORRSTF | PINRSTF, as after the first power-up (SVD
  // reset value 0x0C000000).
  void PowerOn();
  void SetResetFlags(std::uint32_t flags) { csr_ |= flags & csr::kResetFlags; }

  // The world's crystal: how long the HSE takes from HSEON to HSERDY, from the next
  // HSEON on (one already started keeps its time). kNever: a crystal that never starts
  // (cracked, unsoldered, a load capacitance it cannot oscillate with), so HSERDY stays
  // 0 for as long as HSEON is set, SW = HSE never completes and a PLL fed by it never
  // locks. A delay beyond the datasheet's tSU(HSE) is a crystal that starts late (an
  // out-of-spec part, a cold board). A system reset keeps the setting: the crystal is
  // the board's, not the chip's.
  void SetHseStartup(Picoseconds delay) { config_.hse_startup = delay; }
  Picoseconds hse_startup() const { return config_.hse_startup; }

  // Frequencies in Hz; 0 while the source is off or not ready. Asked at every register
  // access (the chip's time, the timers' counting), so computed once per change of the
  // registers or oscillators they depend on.
  double sysclk_hz() const { return clocks().sysclk; }
  double hclk_hz() const { return clocks().hclk; }
  double pclk1_hz() const { return clocks().pclk1; }
  double pclk2_hz() const { return clocks().pclk2; }
  double tim_pclk1_hz() const { return clocks().tim_pclk1; }  // TIM2..7 kernel clock
  double tim_pclk2_hz() const {
    return clocks().tim_pclk2;  // TIM1/8/15/16/17/20 kernel clock
  }
  double pllq_hz() const { return clocks().pllq; }  // 0 unless PLLQEN and locked
  double fdcan_kernel_hz() const { return clocks().fdcan_kernel; }
  // The same truncated to whole hertz (the models count clock edges in integers).
  std::uint64_t sysclk_whole_hz() const { return clocks().sysclk_whole; }
  std::uint64_t tim_pclk1_whole_hz() const { return clocks().tim_pclk1_whole; }
  std::uint64_t tim_pclk2_whole_hz() const { return clocks().tim_pclk2_whole; }
  double lsi_hz() const { return lsi_ready() ? config_.lsi_hz : 0; }
  bool lsi_ready() const { return (csr_ & csr::kLsirdy) != 0; }
  // The IWDG forces the LSI on (RM0440 IWDG: "the LSI is forced ON").
  void ForceLsiOn();
  bool ClockEnabled(Gate g) const;

  // Called with the gate whose reset bit software set (the chip resets that model).
  void SetPeripheralResetHook(std::function<void(Gate)> hook) {
    reset_hook_ = std::move(hook);
  }
  // Called after any change of a frequency (the chip re-checks the clock rules).
  void SetClockChangeHook(std::function<void()> hook) { change_hook_ = std::move(hook); }

  std::uint32_t cfgr() const { return cfgr_; }
  std::uint32_t csr() const { return csr_; }

 private:
  enum Osc { kHsi = 0, kHse = 1, kPll = 2, kLsi = 3 };
  struct Oscillator {
    bool on = false;
    bool ready = false;
    Picoseconds ready_at = kNever;  // when a started oscillator becomes ready
  };
  struct Clocks {
    bool valid = false;
    double sysclk = 0, hclk = 0, pclk1 = 0, pclk2 = 0, tim_pclk1 = 0, tim_pclk2 = 0,
           pllq = 0, fdcan_kernel = 0;
    std::uint64_t sysclk_whole = 0, tim_pclk1_whole = 0, tim_pclk2_whole = 0;
  };
  const Clocks& clocks() const {
    if (!clocks_.valid) Recompute();
    return clocks_;
  }
  void Recompute() const;
  double sysclk_hz_now() const;
  double hclk_hz_now() const;
  double pclk1_hz_now() const;
  double pclk2_hz_now() const;
  double tim_pclk1_hz_now() const;
  double tim_pclk2_hz_now() const;
  double pllq_hz_now() const;
  double fdcan_kernel_hz_now() const;
  // The registers without code of their own (register_table.h).
  static RegisterTable<Rcc> Registers();
  bool WriteRegister(const Access& a);
  void Start(Osc o, Picoseconds delay);
  void Stop(Osc o);
  void UpdateSwitch();
  double PllVcoHz() const;
  double PllInputHz() const;
  void CheckPllConfig();
  void Changed();

  ViolationLog* log_;
  RccConfig config_;
  Picoseconds now_ = 0;
  std::array<Oscillator, 4> osc_{};
  std::uint32_t cr_ = 0, icscr_ = 0, cfgr_ = 0, pllcfgr_ = 0, cier_ = 0, cifr_ = 0;
  std::uint32_t ahb1rstr_ = 0, ahb2rstr_ = 0, ahb3rstr_ = 0, apb1rstr1_ = 0,
                apb1rstr2_ = 0, apb2rstr_ = 0;
  std::uint32_t ahb1enr_ = 0, ahb2enr_ = 0, ahb3enr_ = 0, apb1enr1_ = 0, apb1enr2_ = 0,
                apb2enr_ = 0;
  std::uint32_t ahb1smenr_ = 0, ahb2smenr_ = 0, ahb3smenr_ = 0, apb1smenr1_ = 0,
                apb1smenr2_ = 0, apb2smenr_ = 0;
  std::uint32_t ccipr_ = 0, bdcr_ = 0, csr_ = 0, crrcr_ = 0, ccipr2_ = 0;
  std::function<void(Gate)> reset_hook_;
  std::function<void()> change_hook_;
  mutable Clocks clocks_;
};

// PWR (RM0440 "Power control (PWR)"): the voltage range and Range 1 boost mode the
// clock rules depend on. Other registers are plain storage.
class Pwr final : public Peripheral {
 public:
  static constexpr std::uint32_t kBase = 0x40007000;

  explicit Pwr(ViolationLog* log);
  bool Read(const Access& a, std::uint32_t* value) override;
  bool Write(const Access& a) override;
  void Reset() override;
  void Advance(Picoseconds now) override;
  Picoseconds NextEvent() const override {
    return vosf_until_ > now_ ? vosf_until_ : kNever;
  }

  // Range 1 (VOS = 01) or Range 2 (VOS = 10).
  int voltage_range() const { return static_cast<int>((cr1_ >> 9) & 3u); }
  // Range 1 boost: CR5.R1MODE = 0 (reset value 1 = normal).
  bool boost() const { return voltage_range() == 1 && (cr5_ & (1u << 8)) == 0; }
  void SetChangeHook(std::function<void()> hook) { change_hook_ = std::move(hook); }

 private:
  static RegisterTable<Pwr> Registers();
  // PUCRx/PDCRx at `offset`, or null.
  std::uint32_t* PullRegister(std::uint32_t offset);

  ViolationLog* log_;
  Picoseconds now_ = 0;
  Picoseconds vosf_until_ = 0;
  std::uint32_t cr1_ = 0, cr2_ = 0, cr3_ = 0, cr4_ = 0, sr1_ = 0, cr5_ = 0;
  std::array<std::uint32_t, 14> pucr_pdcr_{};
  std::function<void()> change_hook_;
};

// The manual's frequency limits, checked whenever a clock, the flash latency or the
// voltage range changes (RM0440 PWR "Dynamic voltage scaling management", FLASH "Read
// access latency" table, RCC "System clock (SYSCLK) selection"):
//  - SYSCLK ≤ 170 MHz in Range 1 boost, ≤ 150 MHz in Range 1 normal, ≤ 26 MHz in Range 2;
//  - FLASH_ACR.LATENCY ≥ the wait states HCLK needs in the present range (boost: 0 WS up
//    to 34 MHz, then one more per 34 MHz up to 4 WS at 170 MHz; normal: per 30 MHz; Range
//    2: 12/24/26 MHz), so the latency must be raised before the clock;
//  - SYSCLK may not cross 80 MHz upwards with the AHB prescaler at /1: it is set to /2
//    for the switch and back to /1 only ≥ 1 µs later (this rule rests on ST's HAL,
//    HAL_RCC_ClockConfig, whose comment says the step is necessary).
class ClockRules {
 public:
  ClockRules(ViolationLog* log, const Rcc* rcc, const Pwr* pwr)
      : log_(log), rcc_(rcc), pwr_(pwr) {}
  // `latency` is FLASH_ACR.LATENCY.
  void Check(Picoseconds now, unsigned latency);
  void Reset() {
    last_sysclk_ = 16e6;
    last_hpre_div_ = 1;
    above80_since_ = kNever;
  }
  static unsigned RequiredWaitStates(double hclk_hz, int range, bool boost);

 private:
  ViolationLog* log_;
  const Rcc* rcc_;
  const Pwr* pwr_;
  double last_sysclk_ = 16e6;
  unsigned last_hpre_div_ = 1;
  Picoseconds above80_since_ = kNever;  // when SYSCLK last crossed 80 MHz upwards
};

}  // namespace mjc::g474model
