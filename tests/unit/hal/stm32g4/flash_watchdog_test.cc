// FLASH's key sequence, page erase and double-word programming (RM0440 §5.3, FLASH at
// 0x4002_2000), the watchdog's start sequence and the reset cause (RM0440 §42, IWDG at
// 0x4000_3000; RCC_CSR at 0x4002_1094), and the vector table's layout.
#include <gtest/gtest.h>

#include <array>

#include "hal/stm32g4/flash.h"
#include "hal/stm32g4/vector_table.h"
#include "hal/stm32g4/watchdog.h"
#include "scripted_space.h"

namespace mjc::stm32g4 {
namespace {

using testing::Equals;
using testing::HasBits;
using testing::ScriptedSpace;

constexpr Address kKeyr = 0x40022008, kSr = 0x40022010, kCr = 0x40022014;
constexpr Address kOptr = 0x40022020, kAcr = 0x40022000, kSize = 0x1FFF75E0;
constexpr std::uint32_t kLock = 1u << 31, kPg = 1u, kPer = 2u, kStrt = 1u << 16;

// The flash array as erased, and FLASH_CR's LOCK as the key sequence clears it.
// FLASH_ECCR (0x4002_2018, CMSIS stm32g474xx.h): ADDR_ECC 18:0 (the double word's
// offset in its bank), BK_ECC bit 21, ECCD2 bit 29, ECCC bit 30, ECCD bit 31; the flags
// are cleared by writing 1 to them.
constexpr Address kEccr = 0x40022018;
constexpr std::uint32_t kEccFlags = (1u << 29) | (1u << 30) | (1u << 31);

void ModelFlash(ScriptedSpace& s, std::uint32_t* eccr = nullptr) {
  s.memory[kOptr] = 0xFFEFF8AAu;  // factory option bytes: DBANK = 1
  s.memory[kSize] = 512;
  s.memory[kCr] = kLock;
  s.on_read = [&s, eccr](Address a) -> std::optional<std::uint32_t> {
    if (a == kEccr && eccr != nullptr) return *eccr;
    if (a >= 0x08000000u && a < 0x08080000u && s.memory.count(a) == 0) return 0xFFFFFFFFu;
    return std::nullopt;
  };
  s.after_write = [&s, eccr](Address a, std::uint32_t v) {
    if (a == kKeyr && v == 0xCDEF89ABu && s.WritesTo(kKeyr).size() >= 2 &&
        s.WritesTo(kKeyr)[s.WritesTo(kKeyr).size() - 2] == 0x45670123u) {
      s.memory[kCr] = 0;
    }
    if (a == kEccr && eccr != nullptr) *eccr &= ~(v & kEccFlags);  // write 1 to clear
  };
}

TEST(Stm32g4Flash, ProgramsADoubleWordWithTheKeySequence) {
  ScriptedSpace s;
  ModelFlash(s);
  Stm32g4Flash flash(254, 2);
  ASSERT_TRUE(flash.Init());
  EXPECT_EQ(flash.page_count(), 256u);
  ASSERT_EQ(flash.ProgramDoubleWord(255, 8, 0x1122334455667788ull),
            hal::FlashResult::kOk);
  EXPECT_EQ(s.WritesTo(kKeyr), (std::vector<std::uint32_t>{0x45670123u, 0xCDEF89ABu}));
  // Page 255 = bank 2, 0x0807_F800; the low word first at the 8-aligned address.
  const long pg = s.FirstWrite(kCr, Equals(kPg));
  const long low = s.FirstWrite(0x0807F808u, Equals(0x55667788u));
  const long high = s.FirstWrite(0x0807F80Cu, Equals(0x11223344u));
  const long pg_off = s.FirstWrite(
      kCr, [](std::uint32_t v) { return (v & kPg) == 0; }, pg);
  const long lock = s.FirstWrite(kCr, HasBits(kLock), high);
  for (long i : {pg, low, high, pg_off, lock}) ASSERT_GE(i, 0);
  EXPECT_LT(s.FirstWrite(kKeyr, testing::Any()), pg);
  EXPECT_LT(pg, low);
  EXPECT_LT(low, high);
  EXPECT_LT(high, pg_off);
  EXPECT_LE(pg_off, lock);
  // BSY was polled after the second word.
  bool polled = false;
  for (long i = high; i < pg_off; ++i) {
    polled |= !s.log[static_cast<std::size_t>(i)].write &&
              s.log[static_cast<std::size_t>(i)].address == kSr;
  }
  EXPECT_TRUE(polled);
  // Read back through the register space.
  std::array<std::uint8_t, 8> out{};
  ASSERT_EQ(flash.Read(255, 8, out), hal::FlashResult::kOk);
  EXPECT_EQ(
      out, (std::array<std::uint8_t, 8>{0x88, 0x77, 0x66, 0x55, 0x44, 0x33, 0x22, 0x11}));
}

TEST(Stm32g4Flash, RefusesWhatTheRulesForbid) {
  ScriptedSpace s;
  ModelFlash(s);
  Stm32g4Flash flash(254, 2);
  EXPECT_EQ(flash.ErasePage(254), hal::FlashResult::kHardwareError);  // before Init
  ASSERT_TRUE(flash.Init());
  s.memory[0x0807F000u] = 0x00000000u;  // page 254 offset 0 already written
  s.log.clear();
  EXPECT_EQ(flash.ProgramDoubleWord(254, 0, 1), hal::FlashResult::kNotErased);
  EXPECT_EQ(flash.ProgramDoubleWord(254, 4, 1), hal::FlashResult::kBadAddress);
  EXPECT_EQ(flash.ProgramDoubleWord(254, 2048, 1), hal::FlashResult::kBadAddress);
  EXPECT_EQ(flash.ErasePage(10), hal::FlashResult::kBadAddress);  // the program's page
  EXPECT_EQ(flash.ErasePage(256), hal::FlashResult::kBadAddress);
  EXPECT_EQ(s.CountWritesIn(0x40022000, 0x400220FF), 0);  // FLASH never touched
}

TEST(Stm32g4Flash, ErasesAPageOfBank2) {
  ScriptedSpace s;
  ModelFlash(s);
  Stm32g4Flash flash(200, 1);
  ASSERT_TRUE(flash.Init());
  s.memory[kAcr] = 0x704;
  ASSERT_EQ(flash.ErasePage(200), hal::FlashResult::kOk);
  // PER, PNB = 200 − 128 = 72 at 9:3, BKER (bank 2), then STRT.
  const std::uint32_t cr = kPer | (72u << 3) | (1u << 11);
  const long set = s.FirstWrite(kCr, Equals(cr));
  const long start = s.FirstWrite(kCr, Equals(cr | kStrt));
  ASSERT_GE(set, 0);
  ASSERT_GT(start, set);
  // As ST's HAL sequences an erase (HAL_FLASHEx_Erase, then FLASH_FlushCaches): only
  // the data cache (DCEN, bit 10) is off for the operation, the instruction cache
  // (ICEN, bit 9) stays on until the erase is over; then each is reset (ICRST bit 11,
  // DCRST bit 12) only while it is disabled, and both come back on.
  constexpr std::uint32_t kIcen = 1u << 9, kDcen = 1u << 10, kIcrst = 1u << 11,
                          kDcrst = 1u << 12;
  const long data_off = s.FirstWrite(kAcr, Equals(0x304));
  ASSERT_GE(data_off, 0);
  EXPECT_LT(data_off, start);
  const long icache_off =
      s.FirstWrite(kAcr, [&](std::uint32_t v) { return (v & kIcen) == 0; });
  EXPECT_GT(icache_off, start) << "the instruction cache stays on during the erase";
  const long icrst = s.FirstWrite(kAcr, HasBits(kIcrst));
  const long dcrst = s.FirstWrite(kAcr, HasBits(kDcrst));
  ASSERT_GT(icrst, start);
  ASSERT_GT(dcrst, start);
  for (const auto& access : s.log) {
    if (!access.write || access.address != kAcr) continue;
    if (access.value & kIcrst) {
      EXPECT_EQ(access.value & kIcen, 0u);
    }
    if (access.value & kDcrst) {
      EXPECT_EQ(access.value & kDcen, 0u);
    }
  }
  EXPECT_EQ(s.Peek(kAcr), 0x704u);
  EXPECT_EQ(s.Peek(kCr), kLock);
}

TEST(Stm32g4Flash, AnEccDoubleErrorTakenByTheNmiFailsTheRead) {
  // The scripted read of a corrupt double word raises the NMI there, whose handler the
  // image runs.
  ScriptedSpace s;
  std::uint32_t eccr = 0;
  ModelFlash(s, &eccr);
  Stm32g4Flash flash(254, 2);
  ASSERT_TRUE(flash.Init());
  s.memory[0x0807F808u] = 0x12345678u;  // page 255 offset 8: a cut program's garbage
  const auto erased = s.on_read;
  s.on_read = [&eccr, erased](Address a) -> std::optional<std::uint32_t> {
    if (a == 0x0807F808u || a == 0x0807F80Cu) {
      eccr = (1u << 31) | (1u << 21) | 0x3F808u;
      EXPECT_TRUE(HandleFlashEccNmi());  // the NMI, before the load completes
    }
    return erased(a);
  };
  const std::uint32_t errors = FlashEccErrors();
  std::array<std::uint8_t, 16> out{};
  EXPECT_EQ(flash.Read(255, 0, out), hal::FlashResult::kHardwareError);
  EXPECT_GT(FlashEccErrors(), errors);
  EXPECT_EQ(LastFlashEccAddress(), 0x0807F808u);
  // ECCD cleared by writing 1 to it.
  EXPECT_GE(s.FirstWrite(kEccr, HasBits(1u << 31)), 0);
  // The erased-check before a program reads it too: refused, not programmed.
  s.log.clear();
  EXPECT_EQ(flash.ProgramDoubleWord(255, 8, 0), hal::FlashResult::kHardwareError);
  EXPECT_EQ(s.FirstWrite(kCr, Equals(kPg)), -1);
  // The neighbours read as they are.
  std::array<std::uint8_t, 8> good{};
  EXPECT_EQ(flash.Read(255, 0, good), hal::FlashResult::kOk);
  // An NMI with ECCD clear is not the flash's: the handler says so.
  eccr = 0;
  EXPECT_FALSE(HandleFlashEccNmi());
}

// The NMI comes from the flash interface, so it need not be taken before the driver's
// next instruction: a read whose last double word's error is still pending in ECCR
// (ECCD or the SVD's ECCD2 set, no NMI yet) fails all the same, and the erased-check
// before a program refuses too.
TEST(Stm32g4Flash, AnEccFlagWhoseNmiIsStillPendingFailsTheRead) {
  for (const std::uint32_t flag : {1u << 31, 1u << 29}) {
    ScriptedSpace s;
    std::uint32_t eccr = 0;
    ModelFlash(s, &eccr);
    Stm32g4Flash flash(254, 2);
    ASSERT_TRUE(flash.Init());
    const auto erased = s.on_read;
    s.on_read = [&eccr, erased, flag](Address a) -> std::optional<std::uint32_t> {
      if (a == 0x0807F80Cu) eccr = flag | (1u << 21) | 0x3F808u;  // no NMI taken
      return erased(a);
    };
    const std::uint32_t errors = FlashEccErrors();
    std::array<std::uint8_t, 16> out{};
    EXPECT_EQ(flash.Read(255, 0, out), hal::FlashResult::kHardwareError) << flag;
    EXPECT_EQ(flash.ProgramDoubleWord(255, 8, 0), hal::FlashResult::kHardwareError);
    EXPECT_EQ(s.FirstWrite(kCr, Equals(kPg)), -1) << "programmed over it";
    // The NMI, taken at last, takes either flag and clears it.
    EXPECT_TRUE(HandleFlashEccNmi()) << flag;
    EXPECT_EQ(eccr & kEccFlags, 0u);
    EXPECT_GT(FlashEccErrors(), errors);
    std::array<std::uint8_t, 8> good{};
    EXPECT_EQ(flash.Read(255, 0, good), hal::FlashResult::kOk);
  }
}

TEST(Stm32g4Flash, ErrorFlagsAreReportedAndCleared) {
  ScriptedSpace s;
  ModelFlash(s);
  Stm32g4Flash flash(254, 2);
  ASSERT_TRUE(flash.Init());
  s.after_write = [&s, inner = s.after_write](Address a, std::uint32_t v) {
    inner(a, v);
    if (a == 0x0807F00Cu) s.memory[kSr] = 1u << 4;  // WRPERR after the second word
  };
  EXPECT_EQ(flash.ProgramDoubleWord(254, 8, 0), hal::FlashResult::kHardwareError);
  EXPECT_GE(s.FirstWrite(kSr, HasBits(1u << 4)), 0);  // cleared by writing 1
}

TEST(Stm32g4Flash, RefusesASingleBankDevice) {
  ScriptedSpace s;
  ModelFlash(s);
  s.memory[kOptr] = 0xFFAFF8AAu;  // DBANK = 0
  Stm32g4Flash flash(254, 2);
  EXPECT_FALSE(flash.Init());
}

TEST(Stm32g4Watchdog, StartSequence) {
  ScriptedSpace s;
  ASSERT_EQ(StartWatchdog(), WatchdogResult::kOk);
  EXPECT_EQ(s.WritesTo(0x40003000), (std::vector<std::uint32_t>{0xCCCC, 0x5555, 0xAAAA}));
  EXPECT_EQ(s.Peek(0x40003004), 3u);   // PR: /32
  EXPECT_EQ(s.Peek(0x40003008), 99u);  // RLR
  RefreshWatchdog();
  EXPECT_EQ(s.WritesTo(0x40003000).back(), 0xAAAAu);
}

TEST(Stm32g4Watchdog, ResetCause) {
  ScriptedSpace s;
  s.memory[0x40021094] = (1u << 29) | (1u << 26);  // IWDGRSTF + PINRSTF
  EXPECT_EQ(TakeResetCause(), ResetCause::kIndependentWatchdog);
  EXPECT_TRUE(s.Peek(0x40021094) & (1u << 23));    // RMVF
  s.memory[0x40021094] = (1u << 27) | (1u << 26);  // BORRSTF + PINRSTF
  EXPECT_EQ(TakeResetCause(), ResetCause::kPowerOn);
  s.memory[0x40021094] = 1u << 26;
  EXPECT_EQ(TakeResetCause(), ResetCause::kPin);
  s.memory[0x40021094] = (1u << 28) | (1u << 26);
  EXPECT_EQ(TakeResetCause(), ResetCause::kSoftware);
}

TEST(Stm32g4VectorTable, HandlersSitAt16PlusTheirIrq) {
  const SystemHandlers<int> system{1, 2, 3, 4, 5, 6, 11, 12, 14, 15};
  const std::array<IrqHandler<int>, 2> irqs{{{25, 1025}, {21, 1021}}};
  constexpr int kDefault = -1, kReserved = -2;
  const auto table = BuildVectorTable(system, kDefault, kReserved, irqs);
  ASSERT_EQ(table.size(), 16u + 102u - 1u);
  // Index i is vector position i + 1.
  EXPECT_EQ(table[0], 1);               // Reset at 1
  EXPECT_EQ(table[2], 3);               // HardFault at 3
  EXPECT_EQ(table[6], kReserved);       // 7
  EXPECT_EQ(table[10], 11);             // SVCall at 11
  EXPECT_EQ(table[14], 15);             // SysTick at 15
  EXPECT_EQ(table[16 + 25 - 1], 1025);  // TIM1_UP_TIM16
  EXPECT_EQ(table[16 + 21 - 1], 1021);  // FDCAN1_IT0
  EXPECT_EQ(table[16 + 22 - 1], kDefault);
  EXPECT_EQ(table[16 + 101 - 1], kDefault);  // FMAC, the last
}

}  // namespace
}  // namespace mjc::stm32g4
