#include "hal/stm32g4/watchdog.h"

#include "hal/stm32g4/poll.h"
#include "hal/stm32g4/regs/rcc.h"

namespace mjc::stm32g4 {

WatchdogResult StartWatchdog() {
  const Address kr = iwdg::kBase + iwdg::kKr;
  Write32(kr, iwdg::kr::kStart);
  Write32(kr, iwdg::kr::kUnlock);
  Write32(iwdg::kBase + iwdg::kPr, iwdg::pr::kPr.Value(kWatchdogPrescalerCode));
  Write32(iwdg::kBase + iwdg::kRlr, iwdg::rlr::kRl.Value(kWatchdogReload));
  // The updates cross into the LSI domain (a few LSI periods, ≈ 200 µs); 2^20 reads
  // bound the wait at many ms.
  const bool done = WaitFor(iwdg::kBase + iwdg::kSr,
                            iwdg::sr::kPvu.Bit() | iwdg::sr::kRvu.Bit(), 0, 1u << 20);
  Write32(kr, iwdg::kr::kReload);
  return done ? WatchdogResult::kOk : WatchdogResult::kTimeout;
}

ResetCause TakeResetCause() {
  const Address csr = rcc::kBase + rcc::kCsr;
  const std::uint32_t flags = Read32(csr);
  Write32(csr, flags | rcc::csr::kRmvf.Bit());
  using namespace rcc::csr;
  if (kIwdgrstf.IsSet(flags)) return ResetCause::kIndependentWatchdog;
  if (kWwdgrstf.IsSet(flags)) return ResetCause::kWindowWatchdog;
  if (kSftrstf.IsSet(flags)) return ResetCause::kSoftware;
  if (kLpwrrstf.IsSet(flags)) return ResetCause::kLowPower;
  if (kOblrstf.IsSet(flags)) return ResetCause::kOptionByteLoader;
  if (kBorrstf.IsSet(flags)) return ResetCause::kPowerOn;
  if (kPinrstf.IsSet(flags)) return ResetCause::kPin;
  return ResetCause::kUnknown;
}

}  // namespace mjc::stm32g4
