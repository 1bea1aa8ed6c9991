#include "hal/stm32g4/flash.h"

#include "hal/stm32g4/poll.h"
#include "hal/stm32g4/regs/flash.h"

namespace mjc::stm32g4 {
namespace {

using hal::FlashResult;

constexpr Address kSr = flash::kBase + flash::kSr;
constexpr Address kCr = flash::kBase + flash::kCr;
constexpr Address kAcr = flash::kBase + flash::kAcr;
// A page erase takes up to ~40 ms (datasheet t_ERASE); a register read at 170 MHz takes
// a few cycles, so 2^24 reads (≥ 100 ms) bound every wait.
constexpr std::uint32_t kMaxPolls = 1u << 24;

bool WaitNotBusy() { return WaitFor(kSr, flash::sr::kBsy.Bit(), 0, kMaxPolls); }

// RM0440 §5.3.5 "Flash program and erase operations", unlocking: KEY1 then KEY2 into
// FLASH_KEYR; LOCK then reads 0. (A wrong key locks FLASH_CR until the next reset.)
bool Unlock() {
  if (!flash::cr::kLock.IsSet(Read32(kCr))) return true;
  Write32(flash::kBase + flash::kKeyr, flash::keyr::kKey1);
  Write32(flash::kBase + flash::kKeyr, flash::keyr::kKey2);
  return !flash::cr::kLock.IsSet(Read32(kCr));
}
void Lock() { Write32(kCr, flash::cr::kLock.Bit()); }

// Error flags of the last operation, then cleared (write 1), EOP too.
std::uint32_t TakeErrors() {
  const std::uint32_t errors = Read32(kSr) & flash::sr::kProgramErrors;
  Write32(kSr, errors | flash::sr::kEop.Bit());
  return errors;
}

// The data and instruction caches may hold the old content of a page that is erased or
// programmed (RM0440 §5.3, ART accelerator, "instruction/data cache"); a cache is reset
// (ICRST/DCRST) only while it is disabled. As ST's HAL sequences it (HAL_FLASHEx_Erase,
// HAL_FLASH_Program, then FLASH_FlushCaches): only the data cache is off during the
// operation — the instruction cache stays on, so the control tick, which runs from the
// other bank meanwhile, keeps its cached code for the whole erase (up to ~40 ms) —
// and afterwards each cache that was on is reset and re-enabled: the instruction cache
// disabled for its reset, the data cache still off from the operation.
std::uint32_t DisableDataCache() {
  const std::uint32_t acr = Read32(kAcr);
  Write32(kAcr, acr & ~flash::acr::kDcen.Bit());
  return acr;
}
void ResetAndRestoreCaches(std::uint32_t acr) {
  if (flash::acr::kIcen.IsSet(acr)) {
    const std::uint32_t off = Read32(kAcr) & ~flash::acr::kIcen.Bit();
    Write32(kAcr, off);
    Write32(kAcr, off | flash::acr::kIcrst.Bit());
    Write32(kAcr, off);
    Write32(kAcr, off | flash::acr::kIcen.Bit());
  }
  if (flash::acr::kDcen.IsSet(acr)) {
    const std::uint32_t off = Read32(kAcr) & ~flash::acr::kDcen.Bit();
    Write32(kAcr, off | flash::acr::kDcrst.Bit());
    Write32(kAcr, off);
    Write32(kAcr, off | flash::acr::kDcen.Bit());
  }
}

// The ECC double errors the NMI handler took: how many, and the last one's address.
// Written only by the NMI (HandleFlashEccNmi), read by the calls below around their
// loads (volatile: the NMI lands between two of their instructions).
volatile std::uint32_t g_ecc_errors = 0;
volatile std::uint32_t g_ecc_address = 0;

// Whether a double error was found since `before` (a count of g_ecc_errors): the NMI
// counted one, or a detection flag is still set because the NMI, which a peripheral
// raises, has not been taken yet after the last load. The barrier completes the loads
// before the flag is read.
bool EccErrorSince(std::uint32_t before) {
  DataSyncBarrier();
  if (g_ecc_errors != before) return true;
  const std::uint32_t eccr = Read32(flash::kBase + flash::kEccr);
  return flash::eccr::kEccd.IsSet(eccr) || flash::eccr::kEccd2.IsSet(eccr);
}

FlashResult Finish(std::uint32_t clear_bits, std::uint32_t acr, bool done) {
  const std::uint32_t errors = TakeErrors();
  Write32(kCr, Read32(kCr) & ~clear_bits);
  ResetAndRestoreCaches(acr);
  Lock();
  if (!done) return FlashResult::kHardwareError;
  // PROGERR: the double-word was not erased (RM0440 FLASH_SR.PROGERR).
  if (errors == flash::sr::kProgerr.Bit()) return FlashResult::kNotErased;
  return errors == 0 ? FlashResult::kOk : FlashResult::kHardwareError;
}

}  // namespace

bool Stm32g4Flash::Init() {
  const bool dual_bank = flash::optr::kDbank.IsSet(Read32(flash::kBase + flash::kOptr));
  const std::uint32_t size_kb = Read16(flash::kFlashSizeRegister);
  geometry_ok_ = dual_bank && size_kb == kPages * kPageSize / 1024;
  return geometry_ok_;
}

FlashResult Stm32g4Flash::DoErasePage(std::uint32_t page) {
  if (page >= kPages) return FlashResult::kBadAddress;
  if (!Writable(page))
    return geometry_ok_ ? FlashResult::kBadAddress : FlashResult::kHardwareError;
  // RM0440 §5.3.7 "Flash main memory erase sequences", page erase: no operation
  // ongoing (BSY = 0), error flags of earlier operations cleared, PER with the page and
  // its bank (BKER: bank 2 in dual-bank mode), then STRT, wait BSY = 0, clear PER.
  if (!WaitNotBusy() || !Unlock()) return FlashResult::kHardwareError;
  (void)TakeErrors();
  const std::uint32_t acr = DisableDataCache();
  const std::uint32_t bank = page / kPagesPerBank;
  const std::uint32_t cr = flash::cr::kPer.Bit() |
                           flash::cr::kPnb.Value(page % kPagesPerBank) |
                           (bank == 1 ? flash::cr::kBker.Bit() : 0u);
  Write32(kCr, cr);
  Write32(kCr, cr | flash::cr::kStrt.Bit());
  const bool done = WaitNotBusy();
  return Finish(flash::cr::kPer.Bit() | flash::cr::kPnb.Mask() | flash::cr::kBker.Bit(),
                acr, done);
}

FlashResult Stm32g4Flash::DoProgram(std::uint32_t page, std::uint32_t offset,
                                    std::uint64_t value) {
  if (page >= kPages || offset % kDoubleWord != 0 || offset > kPageSize - kDoubleWord) {
    return FlashResult::kBadAddress;
  }
  if (!Writable(page))
    return geometry_ok_ ? FlashResult::kBadAddress : FlashResult::kHardwareError;
  const Address address = PageAddress(page) + offset;
  // Only an erased double-word may be programmed (its ECC is written once). A double
  // word left corrupt by a cut erase or program reads with an ECC error: the NMI took
  // it, and the page must be erased first.
  const std::uint32_t ecc_before = g_ecc_errors;
  const std::uint32_t low = Read32(address), high = Read32(address + 4);
  if (EccErrorSince(ecc_before)) return FlashResult::kHardwareError;
  if (low != 0xFFFFFFFFu || high != 0xFFFFFFFFu) return FlashResult::kNotErased;
  // RM0440 §5.3.8 "Flash main memory programming sequences", standard programming: BSY
  // = 0, errors cleared, PG = 1, the double-word as two 32-bit writes (low word at the
  // 8-aligned address first), wait BSY = 0, check the flags, PG = 0.
  if (!WaitNotBusy() || !Unlock()) return FlashResult::kHardwareError;
  (void)TakeErrors();
  const std::uint32_t acr = DisableDataCache();
  Write32(kCr, flash::cr::kPg.Bit());
  Write32(address, static_cast<std::uint32_t>(value));
  InstructionSyncBarrier();
  Write32(address + 4, static_cast<std::uint32_t>(value >> 32));
  const bool done = WaitNotBusy();
  return Finish(flash::cr::kPg.Bit(), acr, done);
}

FlashResult Stm32g4Flash::DoRead(std::uint32_t page, std::uint32_t offset,
                                 std::span<std::uint8_t> out) const {
  if (page >= kPages || offset > kPageSize || out.size() > kPageSize - offset) {
    return FlashResult::kBadAddress;
  }
  // Aligned 32-bit reads, bytes taken little-endian. A double word with an ECC double
  // error raises the NMI, whose handler counts it: the read fails.
  const std::uint32_t ecc_before = g_ecc_errors;
  const Address start = PageAddress(page) + offset;
  for (std::size_t i = 0; i < out.size();) {
    const Address a = static_cast<Address>(start + i);
    const std::uint32_t word = Read32(a & ~3u);
    for (std::uint32_t b = a & 3u; b < 4 && i < out.size(); ++b, ++i) {
      out[i] = static_cast<std::uint8_t>(word >> (8 * b));
    }
  }
  return EccErrorSince(ecc_before) ? FlashResult::kHardwareError : FlashResult::kOk;
}

bool HandleFlashEccNmi() {
  const Address eccr = flash::kBase + flash::kEccr;
  const std::uint32_t v = Read32(eccr);
  const std::uint32_t detected =
      v & (flash::eccr::kEccd.Bit() | flash::eccr::kEccd2.Bit());
  if (detected == 0) return false;
  const std::uint32_t bank_offset =
      flash::eccr::kBkEcc.IsSet(v)
          ? Stm32g4Flash::kPagesPerBank * flash::kDualBankPageBytes
          : 0u;
  g_ecc_address = flash::kMainMemory + bank_offset + flash::eccr::kAddrEcc.Get(v);
  // ECCD (ECCD2) is cleared by writing 1; ECCC (also write-1) is left as it is, ECCCIE
  // kept.
  Write32(eccr, (v & flash::eccr::kEcccie.Bit()) | detected);
  g_ecc_errors = g_ecc_errors + 1u;
  return true;
}

std::uint32_t FlashEccErrors() { return g_ecc_errors; }
std::uint32_t LastFlashEccAddress() { return g_ecc_address; }

}  // namespace mjc::stm32g4
