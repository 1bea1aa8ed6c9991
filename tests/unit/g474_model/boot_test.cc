// The option bytes and the boot decision at reset, against RM0440 §2.6 "Boot
// configuration" and §5.4 "FLASH option bytes": FLASH_OPTR programmed through the
// option keys and OPTSTRT, taking effect only at OBL_LAUNCH or a power-on; the boot
// source from nSWBOOT0, nBOOT0, nBOOT1 and PB8. Bit positions are the SVD's (FLASH_OPTR
// nBOOT1 23, nSWBOOT0 26, nBOOT0 27; FLASH_CR OPTSTRT 17, OBL_LAUNCH 27, OPTLOCK 30,
// LOCK 31; FLASH_SR BSY 16, OPTVERR 15; RCC_CSR OBLRSTF 25), written here as numbers so
// that the model's own constants are not what is checked.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <string>

#include "mjc/g474model/virtual_chip.h"

namespace {

using namespace mjc::g474model;

constexpr std::uint32_t kF = 0x40022000, kKeyr = kF + 0x08, kOptkeyr = kF + 0x0C,
                        kSr = kF + 0x10, kCr = kF + 0x14, kOptr = kF + 0x20;
constexpr std::uint32_t kRccCsr = 0x40021000 + 0x94;
constexpr std::uint32_t kNBoot1 = 1u << 23, kNSwBoot0 = 1u << 26, kNBoot0 = 1u << 27;
constexpr std::uint32_t kOptstrt = 1u << 17, kOblLaunch = 1u << 27, kOptlock = 1u << 30,
                        kBsy = 1u << 16, kOptverr = 1u << 15, kOblrstf = 1u << 25;
// RM0440 FLASH_OPTR: the factory word.
constexpr std::uint32_t kFactory = 0xFFEFF8AAu;

ChipConfig WithPin(Boot0Pin pin) {
  ChipConfig c;
  c.boot0 = pin;
  return c;
}

// RM0440 §5.4.2 "Option bytes programming": unlock FLASH_CR, then the option keys, write
// the option register, OPTSTRT, wait for BSY to clear.
void ProgramOptr(VirtualChip& c, std::uint32_t value) {
  c.Write(kKeyr, 0x45670123u, 4);
  c.Write(kKeyr, 0xCDEF89ABu, 4);
  c.Write(kOptkeyr, 0x08192A3Bu, 4);
  c.Write(kOptkeyr, 0x4C5D6E7Fu, 4);
  c.Write(kOptr, value, 4);
  c.Write(kCr, c.Read(kCr, 4) | kOptstrt, 4);
  while (c.Read(kSr, 4) & kBsy) {
  }
}
// Then OBL_LAUNCH: the option-byte loader resets the chip.
void LaunchLoad(VirtualChip& c) { c.Write(kCr, c.Read(kCr, 4) | kOblLaunch, 4); }

constexpr std::uint32_t kFromFlash = (kFactory & ~kNSwBoot0) | kNBoot0;

TEST(G474Boot, FactoryChipWithPb8HighBootsSystemMemory) {
  VirtualChip c(WithPin(Boot0Pin::kPulledUp));
  EXPECT_EQ(c.Read(kOptr, 4), kFactory);
  EXPECT_EQ(c.boot_source(), BootSource::kSystemMemory) << "power-on";
  c.SetResetHandler([](ResetCause) {});
  c.Write(0xE000ED0C, (0x05FAu << 16) | 4u, 4);  // SYSRESETREQ: the pin again
  EXPECT_EQ(c.boot_source(), BootSource::kSystemMemory) << "after a system reset";
  c.PowerCut();
  EXPECT_EQ(c.boot_source(), BootSource::kSystemMemory) << "after a power cycle";
  // And the same chip with PB8 pulled down boots main flash.
  c.SetBoot0Pin(Boot0Pin::kPulledDown);
  c.PowerCut();
  EXPECT_EQ(c.boot_source(), BootSource::kMainFlash);
}

TEST(G474Boot, ProgrammedOptionBytesBootMainFlashWhateverPb8Does) {
  VirtualChip c(WithPin(Boot0Pin::kPulledUp));
  std::optional<ResetCause> cause;
  c.SetResetHandler([&](ResetCause rc) { cause = rc; });
  ProgramOptr(c, kFromFlash);
  EXPECT_EQ(c.boot_source(), BootSource::kSystemMemory) << "not loaded yet";
  LaunchLoad(c);
  ASSERT_TRUE(cause.has_value()) << "OBL_LAUNCH resets the chip";
  EXPECT_EQ(*cause, ResetCause::kOptionLoad);
  EXPECT_TRUE(c.Read(kRccCsr, 4) & kOblrstf);
  EXPECT_EQ(c.Read(kOptr, 4), kFromFlash);
  EXPECT_EQ(c.boot_source(), BootSource::kMainFlash);
  for (const Boot0Pin pin : {Boot0Pin::kPulledUp, Boot0Pin::kFloating,
                             Boot0Pin::kPulledDown, Boot0Pin::kFloating}) {
    c.SetBoot0Pin(pin);
    for (int i = 0; i < 8; ++i) {
      c.Write(0xE000ED0C, (0x05FAu << 16) | 4u, 4);
      EXPECT_EQ(c.boot_source(), BootSource::kMainFlash);
      c.PowerCut();
      EXPECT_EQ(c.boot_source(), BootSource::kMainFlash);
      EXPECT_EQ(c.Read(kOptr, 4), kFromFlash) << "kept across resets and power cuts";
    }
  }
  EXPECT_FALSE(c.violations().Contains("BOOT", "floating"))
      << "nSWBOOT0 = 0: the pin is not sampled";
}

TEST(G474Boot, ANewWordTakesEffectOnlyAtOptionLoadOrPowerOn) {
  VirtualChip c(WithPin(Boot0Pin::kPulledUp));
  c.SetResetHandler([](ResetCause) {});
  ProgramOptr(c, kFromFlash);
  EXPECT_EQ(c.Read(kOptr, 4), kFromFlash) << "the register holds what was written";
  c.Write(0xE000ED0C, (0x05FAu << 16) | 4u, 4);  // a system reset does not load
  EXPECT_EQ(c.Read(kOptr, 4), kFactory);
  EXPECT_EQ(c.boot_source(), BootSource::kSystemMemory);
  c.PowerCut();  // a power-on does
  EXPECT_EQ(c.Read(kOptr, 4), kFromFlash);
  EXPECT_EQ(c.boot_source(), BootSource::kMainFlash);
}

TEST(G474Boot, OptionProgrammingIsBusyForAnOptionPageWrite) {
  VirtualChip c;
  c.Write(kKeyr, 0x45670123u, 4);
  c.Write(kKeyr, 0xCDEF89ABu, 4);
  c.Write(kOptkeyr, 0x08192A3Bu, 4);
  c.Write(kOptkeyr, 0x4C5D6E7Fu, 4);
  c.Write(kOptr, kFromFlash, 4);
  const Picoseconds t0 = c.now();
  c.Write(kCr, c.Read(kCr, 4) | kOptstrt, 4);
  EXPECT_TRUE(c.Read(kSr, 4) & kBsy);
  EXPECT_TRUE(c.Read(kCr, 4) & kOptstrt) << "OPTSTRT reads 1 until BSY clears";
  while (c.Read(kSr, 4) & kBsy) {
  }
  EXPECT_FALSE(c.Read(kCr, 4) & kOptstrt);
  // At least a page erase (DS12288, 22 ms): the option page is erased and programmed.
  EXPECT_GT(static_cast<double>(c.now() - t0) * 1e-12, 20e-3);
}

TEST(G474Boot, NothingChangesWithoutTheOptionKeys) {
  VirtualChip c(WithPin(Boot0Pin::kPulledUp));
  std::optional<ResetCause> cause;
  c.SetResetHandler([&](ResetCause rc) { cause = rc; });
  c.Write(kKeyr, 0x45670123u, 4);
  c.Write(kKeyr, 0xCDEF89ABu, 4);
  EXPECT_TRUE(c.Read(kCr, 4) & kOptlock);
  c.Write(kOptr, kFromFlash, 4);  // OPTLOCK = 1: ignored
  EXPECT_EQ(c.Read(kOptr, 4), kFactory);
  c.Write(kCr, c.Read(kCr, 4) | kOptstrt, 4);
  EXPECT_FALSE(c.Read(kSr, 4) & kBsy) << "OPTSTRT ignored under OPTLOCK";
  LaunchLoad(c);
  EXPECT_FALSE(cause.has_value()) << "OBL_LAUNCH ignored under OPTLOCK";
  // A wrong second option key: a bus error, FLASH_CR and the options locked until reset.
  c.Write(kOptkeyr, 0x08192A3Bu, 4);
  c.Write(kOptkeyr, 0x12345678u, 4);
  EXPECT_TRUE(c.violations().Contains("bus", "OPTKEYR"));
  EXPECT_TRUE(c.Read(kCr, 4) & (1u << 31));
  ProgramOptr(c, kFromFlash);  // the keys again: refused until a reset
  EXPECT_EQ(c.Read(kOptr, 4), kFactory);
  c.PowerCut();
  EXPECT_EQ(c.Read(kOptr, 4), kFactory);
  EXPECT_EQ(c.boot_source(), BootSource::kSystemMemory);
}

TEST(G474Boot, NBoot1SelectsSramAndNBoot0AloneSelectsTheRom) {
  VirtualChip c(WithPin(Boot0Pin::kPulledDown));
  c.SetResetHandler([](ResetCause) {});
  // nSWBOOT0 = 0, nBOOT0 = 0: BOOT0 = 1 from the option bit, nBOOT1 = 1 → system memory.
  ProgramOptr(c, kFactory & ~(kNSwBoot0 | kNBoot0));
  LaunchLoad(c);
  EXPECT_EQ(c.boot_source(), BootSource::kSystemMemory) << "PB8 low does not matter";
  // nBOOT1 = 0 as well → embedded SRAM.
  ProgramOptr(c, kFactory & ~(kNSwBoot0 | kNBoot0 | kNBoot1));
  LaunchLoad(c);
  EXPECT_EQ(c.boot_source(), BootSource::kSram);
}

TEST(G474Boot, AFloatingPb8BootsByChance) {
  VirtualChip c(WithPin(Boot0Pin::kFloating));
  c.SetResetHandler([](ResetCause) {});
  int rom = 0, flash = 0;
  for (int i = 0; i < 64; ++i) {
    c.PowerCut();
    (c.boot_source() == BootSource::kSystemMemory ? rom : flash)++;
  }
  EXPECT_GT(rom, 0);
  EXPECT_GT(flash, 0);
  EXPECT_TRUE(c.violations().Contains("BOOT", "floating"));
}

TEST(G474Boot, APowerCutDuringOptionProgrammingIsOptverrAndTheFactoryWord) {
  VirtualChip c(WithPin(Boot0Pin::kPulledUp));
  c.SetResetHandler([](ResetCause) {});
  c.Write(kKeyr, 0x45670123u, 4);
  c.Write(kKeyr, 0xCDEF89ABu, 4);
  c.Write(kOptkeyr, 0x08192A3Bu, 4);
  c.Write(kOptkeyr, 0x4C5D6E7Fu, 4);
  c.Write(kOptr, kFromFlash, 4);
  c.Write(kCr, c.Read(kCr, 4) | kOptstrt, 4);
  c.AdvanceTo(c.now() + 5'000'000'000);  // 5 ms into the option page's erase
  c.PowerCut();
  EXPECT_TRUE(c.Read(kSr, 4) & kOptverr);
  EXPECT_EQ(c.Read(kOptr, 4), kFactory);
  EXPECT_EQ(c.boot_source(), BootSource::kSystemMemory);
  c.Write(0xE000ED0C, (0x05FAu << 16) | 4u, 4);
  EXPECT_TRUE(c.Read(kSr, 4) & kOptverr) << "set again after each system reset";
  // Programming the word whole heals it.
  ProgramOptr(c, kFromFlash);
  LaunchLoad(c);
  EXPECT_FALSE(c.Read(kSr, 4) & kOptverr);
  EXPECT_EQ(c.boot_source(), BootSource::kMainFlash);
}

TEST(G474Boot, OptionBytesAreKeptInThePersistenceFile) {
  const std::string path =
      ::testing::TempDir() + "g474_options_" + std::to_string(::getpid()) + ".bin";
  std::remove(path.c_str());
  ChipConfig config = WithPin(Boot0Pin::kPulledUp);
  config.flash.path = path;
  {
    VirtualChip c(config);
    EXPECT_EQ(c.boot_source(), BootSource::kSystemMemory);
    c.SetResetHandler([](ResetCause) {});
    ProgramOptr(c, kFromFlash);
    LaunchLoad(c);
  }
  {
    VirtualChip c(config);  // the same board powered up again
    EXPECT_EQ(c.Read(kOptr, 4), kFromFlash);
    EXPECT_EQ(c.boot_source(), BootSource::kMainFlash);
  }
  // A file of the array alone (written before the option bytes were kept) is still
  // taken: the array as it was, the factory options.
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    std::string zeros(512 * 1024, '\0');
    out.write(zeros.data(), static_cast<std::streamsize>(zeros.size()));
  }
  {
    VirtualChip c(config);
    EXPECT_EQ(c.Read(0x08000000, 4), 0u);
    EXPECT_EQ(c.Read(kOptr, 4), kFactory);
  }
  std::remove(path.c_str());
}

TEST(G474Boot, AChipBootedOutsideMainFlashIsSilentUntilReset) {
  VirtualChip c(WithPin(Boot0Pin::kPulledUp));
  bool reset = false;
  c.SetResetHandler([&](ResetCause) {
    reset = true;
    throw ChipReset{ResetCause::kPowerCut};
  });
  int frames = 0;
  c.fdcan1().SetTransmitHook([&](const CanBusFrame&, Picoseconds) { ++frames; });
  c.SetBoot0Pin(Boot0Pin::kPulledDown);  // someone fits the pull-down…
  c.Schedule(Microseconds(50000), [&] { c.PowerCut(); });  // …and cycles the power
  ASSERT_EQ(c.boot_source(), BootSource::kSystemMemory);
  EXPECT_THROW(c.RunWithoutImage(), ChipReset);
  EXPECT_TRUE(reset);
  EXPECT_GE(c.now(), Microseconds(50000));
  EXPECT_EQ(frames, 0);
  EXPECT_EQ(c.boot_source(), BootSource::kMainFlash);
}

}  // namespace
