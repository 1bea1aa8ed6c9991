#include "mjc/boot/g474_platform.h"

#include "hal/stm32g4/clock.h"
#include "hal/stm32g4/gpio.h"
#include "hal/stm32g4/mmio.h"
#include "hal/stm32g4/poll.h"
#include "hal/stm32g4/regs/cortex_m4.h"
#include "hal/stm32g4/regs/flash.h"
#include "hal/stm32g4/regs/rcc.h"

namespace mjc::boot::g474 {
namespace {

using stm32g4::Address;
using stm32g4::Read32;
using stm32g4::Write32;
namespace rcc = stm32g4::rcc;

// The bridge's enable low from the moment it is an output (pins.h of the joint board:
// the same pin and level).
constexpr stm32g4::PinConfig kBridgeEnable = {.pin = {stm32g4::Port::kB, 10},
                                              .mode = stm32g4::PinMode::kOutput,
                                              .pull = stm32g4::Pull::kDown,
                                              .initial_high = false};
constexpr stm32g4::PinConfig kCanPins[] = {
    {.pin = {stm32g4::Port::kA, 11},
     .mode = stm32g4::PinMode::kAlternate,
     .alternate = 9,
     .pull = stm32g4::Pull::kUp},  // FDCAN1_RX
    {.pin = {stm32g4::Port::kA, 12},
     .mode = stm32g4::PinMode::kAlternate,
     .alternate = 9,
     .speed = stm32g4::Speed::kHigh},  // FDCAN1_TX
};

constexpr Address kUid = 0x1FFF7590u;
// A bounded wait for the clock switches (as clock.cc bounds its own).
constexpr std::uint32_t kMaxPolls = 1u << 20;
// RCC reset values (RM0440 §7.4; PLLCFGR: PLLN = 16).
constexpr std::uint32_t kPllcfgrReset = 0x00001000u;
constexpr std::uint32_t kSwHsi16 = 0b01;
constexpr std::uint32_t kHpreDiv1 = 0b0000, kHpreDiv2 = 0b1000;

void SetBits(Address a, std::uint32_t bits) { Write32(a, Read32(a) | bits); }
void ClearBits(Address a, std::uint32_t bits) { Write32(a, Read32(a) & ~bits); }

// A peripheral through its RCC reset bit: set, read back, cleared (RM0440
// RCC_AHB2RSTR, RCC_APB1RSTR1: the peripheral is held in reset while its bit is set).
void PulseReset(Address reg, std::uint32_t bits) {
  SetBits(reg, bits);
  (void)Read32(reg);
  ClearBits(reg, bits);
}

}  // namespace

ResetFlags PeekResetFlags() {
  const std::uint32_t flags = Read32(rcc::kBase + rcc::kCsr);
  using namespace rcc::csr;
  ResetFlags r;
  r.software = kSftrstf.IsSet(flags);
  // RCC_CSR's top byte: OBLRSTF (bit 25) up to LPWRRSTF (bit 31); bit 24 is reserved.
  static_assert(kOblrstf.Bit() == 1u << 25);
  r.flags = static_cast<std::uint8_t>(flags >> 24);
  // The most specific cause first, as the application's TakeResetCause() orders them.
  if (kIwdgrstf.IsSet(flags) || kWwdgrstf.IsSet(flags)) {
    r.cause = protocol::ResetCause::kWatchdog;
  } else if (kSftrstf.IsSet(flags)) {
    r.cause = protocol::ResetCause::kSoftware;
  } else if (kLpwrrstf.IsSet(flags) || kOblrstf.IsSet(flags)) {
    r.cause = protocol::ResetCause::kOther;
  } else if (kBorrstf.IsSet(flags)) {
    r.cause = protocol::ResetCause::kPowerOn;
  } else if (kPinrstf.IsSet(flags)) {
    r.cause = protocol::ResetCause::kPin;
  }
  return r;
}

void ClearResetFlags() {
  const Address csr = rcc::kBase + rcc::kCsr;
  Write32(csr, Read32(csr) | rcc::csr::kRmvf.Bit());
}

void HoldBridgeOff() {
  const Address ahb2enr = rcc::kBase + rcc::kAhb2enr;
  SetBits(ahb2enr, rcc::ahb2enr::kGpioben.Bit());
  (void)Read32(ahb2enr);  // usable once the enable has reached it (RM0440 §7.2.17)
  stm32g4::ConfigurePin(kBridgeEnable);
}

void EnableCanPeripherals() {
  const Address ahb2enr = rcc::kBase + rcc::kAhb2enr;
  SetBits(ahb2enr, rcc::ahb2enr::kGpioaen.Bit());
  (void)Read32(ahb2enr);
  for (const stm32g4::PinConfig& pin : kCanPins) stm32g4::ConfigurePin(pin);
  // FDCAN's kernel clock is chosen before its register clock starts: PLLQ (01).
  const Address ccipr = rcc::kBase + rcc::kCcipr;
  Write32(ccipr, rcc::ccipr::kFdcansel.With(Read32(ccipr), 0b01));
  const Address apb1enr1 = rcc::kBase + rcc::kApb1enr1;
  SetBits(apb1enr1, rcc::apb1enr1::kFdcanen.Bit());
  (void)Read32(apb1enr1);
}

std::uint32_t OptionBytes() {
  return Read32(stm32g4::flash::kBase + stm32g4::flash::kOptr);
}

std::uint16_t BoardInstance() {
  std::uint32_t folded = 0;
  for (Address a = kUid; a < kUid + 12; a += 4) folded ^= Read32(a);
  return static_cast<std::uint16_t>(folded ^ (folded >> 16));
}

std::uint32_t MsClock::Now() {
  const std::uint32_t now = stm32g4::CycleCount();
  if (!started_) {
    started_ = true;
    last_ = now;
    return 0;
  }
  // Whole milliseconds carried, the rest kept: no drift over any run. 32-bit
  // arithmetic (no 64-bit division in the image): the elapsed cycles plus a remainder
  // below one millisecond's stay below 2^32 while Now() runs once per wrap less 1 ms.
  const std::uint32_t cycles = (now - last_) + remainder_;
  last_ = now;
  ms_ += cycles / cycles_per_ms_;
  remainder_ = cycles % cycles_per_ms_;
  return ms_;
}

void ReleasePeripherals() {
  // NVIC: nothing enabled, nothing pending (ARMv7-M B3.4: ICER/ICPR, write 1 clears).
  for (std::uint32_t i = 0; i < 4; ++i) {
    Write32(stm32g4::nvic::kBase + stm32g4::nvic::kIcer0 + 4 * i, 0xFFFFFFFFu);
  }
  stm32g4::DataSyncBarrier();
  stm32g4::InstructionSyncBarrier();
  for (std::uint32_t i = 0; i < 4; ++i) {
    Write32(stm32g4::nvic::kBase + stm32g4::nvic::kIcpr0 + 4 * i, 0xFFFFFFFFu);
  }

  // FDCAN1 and the GPIO ports through their reset bits, then their clocks off and
  // FDCAN's kernel clock selection back to its reset value.
  PulseReset(rcc::kBase + rcc::kApb1rstr1, rcc::apb1rstr1::kFdcanrst.Bit());
  ClearBits(rcc::kBase + rcc::kApb1enr1, rcc::apb1enr1::kFdcanen.Bit());
  const Address ccipr = rcc::kBase + rcc::kCcipr;
  Write32(ccipr, rcc::ccipr::kFdcansel.With(Read32(ccipr), 0));
  PulseReset(rcc::kBase + rcc::kAhb2rstr,
             rcc::ahb2rstr::kGpioarst.Bit() | rcc::ahb2rstr::kGpiobrst.Bit());
  ClearBits(rcc::kBase + rcc::kAhb2enr,
            rcc::ahb2enr::kGpioaen.Bit() | rcc::ahb2enr::kGpioben.Bit());

  // The clock tree back to HSI16. Leaving a SYSCLK above 80 MHz goes through AHB /2
  // (ST's HAL, HAL_RCC_ClockConfig: "transition state management when switching from
  // PLL with frequency above 80 MHz"), as the bring-up did on the way up.
  const Address cfgr = rcc::kBase + rcc::kCfgr;
  Write32(cfgr, rcc::cfgr::kHpre.With(Read32(cfgr), kHpreDiv2));
  Write32(cfgr, rcc::cfgr::kSw.With(Read32(cfgr), kSwHsi16));
  (void)stm32g4::WaitFor(cfgr, rcc::cfgr::kSws.Mask(), rcc::cfgr::kSws.Value(kSwHsi16),
                         kMaxPolls);
  std::uint32_t word = Read32(cfgr);
  word = rcc::cfgr::kHpre.With(word, kHpreDiv1);
  word = rcc::cfgr::kPpre1.With(word, 0);
  word = rcc::cfgr::kPpre2.With(word, 0);
  Write32(cfgr, word);
  const Address cr = rcc::kBase + rcc::kCr;
  ClearBits(cr, rcc::cr::kPllon.Bit());
  (void)stm32g4::WaitFor(cr, rcc::cr::kPllrdy.Bit(), 0, kMaxPolls);
  Write32(rcc::kBase + rcc::kPllcfgr, kPllcfgrReset);
  ClearBits(cr, rcc::cr::kHseon.Bit());
  (void)stm32g4::WaitFor(cr, rcc::cr::kHserdy.Bit(), 0, kMaxPolls);
}

}  // namespace mjc::boot::g474
