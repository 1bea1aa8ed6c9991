#include "hal/stm32g4/clock.h"

#include "hal/stm32g4/mmio.h"
#include "hal/stm32g4/poll.h"
#include "hal/stm32g4/regs/flash.h"
#include "hal/stm32g4/regs/pwr.h"
#include "hal/stm32g4/regs/rcc.h"

namespace mjc::stm32g4 {
namespace {

// Polls are bounded generously: PLL lock ~100 µs, the others a few cycles; at 16 MHz a
// register read is ≥ 2 cycles, so 2^20 reads last ≥ 130 ms (the service hook keeps an
// inherited watchdog fed meanwhile). The HSE's wait has its own bound in time
// (kHseTimeoutMs, clock.h).
constexpr std::uint32_t kMaxPolls = 1u << 20;

// CFGR.HPRE codes (RM0440 §7.4.3): 0xxx = /1, 1000 = /2.
constexpr std::uint32_t kHpreDiv1 = 0b0000;
constexpr std::uint32_t kHpreDiv2 = 0b1000;
// CFGR.PPREx: 0xx = /1.
constexpr std::uint32_t kPpreDiv1 = 0b000;
// CFGR.SW / SWS: 01 = HSI16, 10 = HSE, 11 = PLLRCLK.
constexpr std::uint32_t kSwHsi16 = 0b01;
constexpr std::uint32_t kSwPll = 0b11;
// PLLCFGR.PLLSRC: 10 = HSI16, 11 = HSE. PLLR/PLLQ: 00 = /2, 01 = /4.
constexpr std::uint32_t kPllSrcHsi = 0b10;
constexpr std::uint32_t kPllSrcHse = 0b11;
constexpr std::uint32_t PllDivCode(std::uint32_t div) { return div / 2 - 1; }
// CCIPR.FDCANSEL: 01 = PLLQ.
constexpr std::uint32_t kFdcanSelPllq = 0b01;
// PWR_CR1.VOS: 01 = Range 1.
constexpr std::uint32_t kVosRange1 = 0b01;

// The intermediate AHB /2 step must last ≥ 1 µs (RM0440 §6.1.5). The CPU runs at
// 85 MHz then; 170 cycles are 2 µs.
constexpr std::uint32_t kIntermediateCycles = kSysclkHz / 1'000'000;

void SetBits(Address a, std::uint32_t bits) { Write32(a, Read32(a) | bits); }
void ClearBits(Address a, std::uint32_t bits) { Write32(a, Read32(a) & ~bits); }

// WaitFor (poll.h) with the service hook called between the reads.
bool Wait(Address address, std::uint32_t mask, std::uint32_t expected,
          ClockService service) {
  for (std::uint32_t i = 0; i < kMaxPolls; ++i) {
    if ((Read32(address) & mask) == expected) return true;
    if (service != nullptr) service();
  }
  return false;
}

// HSERDY within kHseTimeoutCycles of the cycle counter (HCLK 8 MHz here). Each pass
// also counts as at least one cycle, so the wait ends where the counter does not count
// (a debugger's halt, an emulator without a DWT), as CycleCounter::WaitSince does.
bool WaitForHse(ClockService service) {
  const Address rcc_cr = rcc::kBase + rcc::kCr;
  const std::uint32_t start = CycleCount();
  for (std::uint32_t pass = 0;
       pass < kHseTimeoutCycles && CycleCount() - start < kHseTimeoutCycles; ++pass) {
    if (rcc::cr::kHserdy.IsSet(Read32(rcc_cr))) return true;
    if (service != nullptr) service();
  }
  return rcc::cr::kHserdy.IsSet(Read32(rcc_cr));
}

// From HSI16 (reset, or a bring-up that failed) to 170 MHz from `pll_source` with
// input divider `pll_m`; the HSE is started and waited for first when it is the source.
ClockResult BringUp(std::uint32_t pll_source, std::uint32_t pll_m, ClockService service) {
  EnableCycleCounter();
  const Address rcc_cr = rcc::kBase + rcc::kCr;
  constexpr Address cfgr = rcc::kBase + rcc::kCfgr;
  // A step that fails leaves SYSCLK on HSI16 and AHB back at /1 (16 MHz).
  const auto fail = [](ClockResult result) {
    Write32(cfgr, rcc::cfgr::kHpre.With(Read32(cfgr), kHpreDiv1));
    return result;
  };

  // 1. PWR's register clock, read back so the enable has taken effect before PWR is
  //    written (RM0440 §7.2.17, a peripheral is usable 2 cycles after its enable).
  const Address apb1enr1 = rcc::kBase + rcc::kApb1enr1;
  SetBits(apb1enr1, rcc::apb1enr1::kPwren.Bit());
  (void)Read32(apb1enr1);

  // 2. RM0440 §6.1.5, from Range 1 normal to Range 1 boost: (1) the AHB prescaler
  //    divides by 2 before the switch to the higher frequency (ST's HAL: "intermediate
  //    step with HCLK prescaler 2 necessary before to go over 80 MHz"; HCLK is 8 MHz
  //    meanwhile); (2) clear R1MODE; (3) raise the wait states; (4) switch; (5) after
  //    ≥ 1 µs, the final AHB prescaler. Boost is needed above 150 MHz. Still on HSI16.
  Write32(cfgr, rcc::cfgr::kHpre.With(Read32(cfgr), kHpreDiv2));
  // PWR_CR5.R1MODE = 0. The regulator's flag (PWR_SR2.VOSF) concerns a change of the
  // voltage range (CR1.VOS), not of R1MODE: ST's HAL (HAL_PWREx_ControlVoltageScaling)
  // only clears R1MODE when the range is already 1 — Range 1 is the reset value — and
  // waits for VOSF only when it has to leave Range 2 first. So does this.
  const Address cr1 = pwr::kBase + pwr::kCr1;
  const Address cr5 = pwr::kBase + pwr::kCr5;
  ClearBits(cr5, pwr::cr5::kR1mode.Bit());
  if (pwr::cr1::kVos.Get(Read32(cr1)) != kVosRange1) {
    Write32(cr1, pwr::cr1::kVos.With(Read32(cr1), kVosRange1));
    if (!Wait(pwr::kBase + pwr::kSr2, pwr::sr2::kVosf.Bit(), 0, service)) {
      return fail(ClockResult::kVoltageTimeout);
    }
  }

  // 3. Flash latency before the frequency rises (RM0440 §5.3.3: increase the wait states
  //    first and check them by reading FLASH_ACR back), with prefetch and both caches
  //    on (§5.3.4/§5.3.5: the ART accelerator hides most of the 4 wait states).
  const Address acr = flash::kBase + flash::kAcr;
  Write32(acr, flash::acr::kLatency.With(Read32(acr), kFlashWaitStates) |
                   flash::acr::kPrften.Bit() | flash::acr::kIcen.Bit() |
                   flash::acr::kDcen.Bit());
  if (!Wait(acr, flash::acr::kLatency.Mask(),
            flash::acr::kLatency.Value(kFlashWaitStates), service)) {
    return fail(ClockResult::kFlashLatency);
  }

  // 4. HSE (a crystal: HSEBYP stays 0), wait HSERDY (RM0440 §7.2.1) for kHseTimeoutMs.
  if (pll_source == kPllSrcHse) {
    SetBits(rcc_cr, rcc::cr::kHseon.Bit());
    if (!WaitForHse(service)) return fail(ClockResult::kHseTimeout);
  }

  // 5. The PLL is configured only while it is off and unlocked (RM0440 §7.2.4): clear
  //    PLLON, wait PLLRDY = 0, program M/N/R/Q and the outputs, then PLLON, wait PLLRDY.
  ClearBits(rcc_cr, rcc::cr::kPllon.Bit());
  if (!Wait(rcc_cr, rcc::cr::kPllrdy.Bit(), 0, service)) {
    return fail(ClockResult::kPllTimeout);
  }
  Write32(rcc::kBase + rcc::kPllcfgr,
          rcc::pllcfgr::kPllsrc.Value(pll_source) | rcc::pllcfgr::kPllm.Value(pll_m - 1) |
              rcc::pllcfgr::kPlln.Value(kPllN) |
              rcc::pllcfgr::kPllr.Value(PllDivCode(kPllR)) | rcc::pllcfgr::kPllren.Bit() |
              rcc::pllcfgr::kPllq.Value(PllDivCode(kPllQ)) | rcc::pllcfgr::kPllqen.Bit());
  SetBits(rcc_cr, rcc::cr::kPllon.Bit());
  if (!Wait(rcc_cr, rcc::cr::kPllrdy.Bit(), rcc::cr::kPllrdy.Bit(), service)) {
    return fail(ClockResult::kPllTimeout);
  }

  // 6. SYSCLK = PLLRCLK (HCLK 85 MHz through the /2 of step 2), wait SWS.
  Write32(cfgr, rcc::cfgr::kSw.With(Read32(cfgr), kSwPll));
  if (!Wait(cfgr, rcc::cfgr::kSws.Mask(), rcc::cfgr::kSws.Value(kSwPll), service)) {
    return fail(ClockResult::kSwitchTimeout);
  }

  // 7. ≥ 1 µs at the intermediate frequency, then AHB /1 (170 MHz) and both APB /1.
  WaitCyclesSince(CycleCount(), kIntermediateCycles);
  std::uint32_t word = Read32(cfgr);
  word = rcc::cfgr::kHpre.With(word, kHpreDiv1);
  word = rcc::cfgr::kPpre1.With(word, kPpreDiv1);
  word = rcc::cfgr::kPpre2.With(word, kPpreDiv1);
  Write32(cfgr, word);
  return ClockResult::kOk;
}

}  // namespace

ClockResult ConfigureClocks(ClockService service) {
  return BringUp(kPllSrcHse, kPllM, service);
}

ClockResult ConfigureClocksFromHsi(ClockService service) {
  return BringUp(kPllSrcHsi, kPllMHsi, service);
}

ClockSource ActiveClockSource() {
  const std::uint32_t sws = rcc::cfgr::kSws.Get(Read32(rcc::kBase + rcc::kCfgr));
  if (sws == kSwHsi16) return ClockSource::kHsi16;
  if (sws != kSwPll) return ClockSource::kOther;
  switch (rcc::pllcfgr::kPllsrc.Get(Read32(rcc::kBase + rcc::kPllcfgr))) {
    case kPllSrcHse:
      return ClockSource::kHsePll;
    case kPllSrcHsi:
      return ClockSource::kHsiPll;
    default:
      return ClockSource::kOther;
  }
}

bool HseReady() { return rcc::cr::kHserdy.IsSet(Read32(rcc::kBase + rcc::kCr)); }

void EnablePeripheralClocks() {
  // Each enable is read back: RM0440 §7.2.17 ("Peripheral clock enable register"), the
  // peripheral may be accessed only after the enable has reached it.
  const Address ahb2enr = rcc::kBase + rcc::kAhb2enr;
  SetBits(ahb2enr, rcc::ahb2enr::kGpioaen.Bit() | rcc::ahb2enr::kGpioben.Bit() |
                       rcc::ahb2enr::kGpiocen.Bit());
  (void)Read32(ahb2enr);
  const Address apb2enr = rcc::kBase + rcc::kApb2enr;
  SetBits(apb2enr, rcc::apb2enr::kSyscfgen.Bit() | rcc::apb2enr::kTim1en.Bit() |
                       rcc::apb2enr::kSpi1en.Bit());
  (void)Read32(apb2enr);
  // FDCAN's kernel clock is chosen before its register clock starts.
  const Address ccipr = rcc::kBase + rcc::kCcipr;
  Write32(ccipr, rcc::ccipr::kFdcansel.With(Read32(ccipr), kFdcanSelPllq));
  const Address apb1enr1 = rcc::kBase + rcc::kApb1enr1;
  SetBits(apb1enr1, rcc::apb1enr1::kTim3en.Bit() | rcc::apb1enr1::kFdcanen.Bit());
  (void)Read32(apb1enr1);
}

}  // namespace mjc::stm32g4
