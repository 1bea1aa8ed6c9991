// FLASH against RM0440 §5: the key sequence and its lock, erase/program rules and
// their error flags, busy times, power cuts (seeded), and the ECC double errors a cut
// leaves (FLASH_ECCR bit positions from ST's CMSIS header stm32g474xx.h: ADDR_ECC 18:0,
// BK_ECC 21, ECCD 31).
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "mjc/g474model/virtual_chip.h"

namespace {

using namespace mjc::g474model;

constexpr std::uint32_t kF = 0x40022000, kKeyr = kF + 0x08, kSr = kF + 0x10,
                        kCr = kF + 0x14, kEccr = kF + 0x18;
constexpr std::uint32_t kEccd = 0x80000000u, kBkEcc = 0x00200000u;

void Unlock(VirtualChip& c) {
  c.Write(kKeyr, Flash::kKey1, 4);
  c.Write(kKeyr, Flash::kKey2, 4);
}
void WaitIdle(VirtualChip& c) {
  while (c.Read(kSr, 4) & Flash::kBsy) {
  }
}
void ErasePage(VirtualChip& c, std::uint32_t page, bool bank2) {
  c.Write(kCr, (1u << 1) | (page << 3) | (bank2 ? 1u << 11 : 0), 4);
  c.Write(kCr, c.Read(kCr, 4) | (1u << 16), 4);
  WaitIdle(c);
  c.Write(kCr, 0, 4);
}
void Program(VirtualChip& c, std::uint32_t address, std::uint64_t v) {
  c.Write(kCr, 1u, 4);
  c.Write(address, static_cast<std::uint32_t>(v), 4);
  c.Write(address + 4, static_cast<std::uint32_t>(v >> 32), 4);
  WaitIdle(c);
  c.Write(kCr, 0, 4);
}

TEST(G474Flash, LockedUntilTheKeysAndAWrongKeyLocksUntilReset) {
  VirtualChip c;
  c.SetResetHandler([](ResetCause) {});
  EXPECT_TRUE(c.Read(kCr, 4) & (1u << 31));
  c.Write(kKeyr, Flash::kKey1, 4);
  c.Write(kKeyr, 0x12345678, 4);  // wrong second key
  EXPECT_TRUE(c.violations().Contains("bus", "KEYR"));
  Unlock(c);
  EXPECT_TRUE(c.Read(kCr, 4) & (1u << 31)) << "a wrong key locks until reset";
  c.Write(0xE000ED0C, (0x05FAu << 16) | 4u, 4);  // system reset
  Unlock(c);
  EXPECT_FALSE(c.Read(kCr, 4) & (1u << 31));
}

TEST(G474Flash, EraseAndProgramTakeTheirDatasheetTimes) {
  VirtualChip c;
  Unlock(c);
  const Picoseconds t0 = c.now();
  ErasePage(c, 5, false);
  EXPECT_NEAR(static_cast<double>(c.now() - t0) * 1e-12, 22.02e-3, 1e-5);
  const Picoseconds t1 = c.now();
  Program(c, 0x08000000 + 5 * 2048, 0x1122334455667788ull);
  EXPECT_NEAR(static_cast<double>(c.now() - t1) * 1e-12, 81.7e-6, 2e-6);
  EXPECT_EQ(c.Read(0x08000000 + 5 * 2048, 4), 0x55667788u);
  EXPECT_EQ(c.Read(0x08000000 + 5 * 2048 + 4, 4), 0x11223344u);
  EXPECT_EQ(c.Read(kSr, 4), 0u) << "EOP only with EOPIE";
}

TEST(G474Flash, BankTwoPagesAreSelectedByBker) {
  VirtualChip c;
  Unlock(c);
  Program(c, 0x08040000 + 3 * 2048, 0);  // all zeros: allowed anywhere
  ErasePage(c, 3, /*bank2=*/false);      // bank 1 page 3: not ours
  EXPECT_EQ(c.Read(0x08040000 + 3 * 2048, 4), 0u);
  ErasePage(c, 3, /*bank2=*/true);
  EXPECT_EQ(c.Read(0x08040000 + 3 * 2048, 4), 0xFFFFFFFFu);
}

TEST(G474Flash, ProgrammingErrors) {
  VirtualChip c;
  Unlock(c);
  const std::uint32_t a = 0x08001000;
  Program(c, a, 0xAAAAAAAAAAAAAAAAull);
  Program(c, a, 0x5555555555555555ull);  // not erased
  EXPECT_TRUE(c.Read(kSr, 4) & Flash::kProgerr);
  EXPECT_EQ(c.Read(a, 4), 0xAAAAAAAAu);
  c.Write(kSr, Flash::kProgerr, 4);  // write 1 to clear
  EXPECT_EQ(c.Read(kSr, 4), 0u);
  Program(c, a, 0);  // all zeros over a programmed double word: allowed
  EXPECT_EQ(c.Read(kSr, 4), 0u);
  EXPECT_EQ(c.Read(a, 4), 0u);
  // First word not 8-aligned.
  c.Write(kCr, 1u, 4);
  c.Write(a + 12, 1, 4);
  EXPECT_TRUE(c.Read(kSr, 4) & Flash::kPgaerr);
  c.Write(kSr, 0xFFFF, 4);
  // Half-word write.
  c.Write(a + 16, 1, 2);
  EXPECT_TRUE(c.Read(kSr, 4) & Flash::kSizerr);
  c.Write(kSr, 0xFFFF, 4);
  // Second word elsewhere.
  c.Write(a + 16, 1, 4);
  c.Write(a + 24, 1, 4);
  EXPECT_TRUE(c.Read(kSr, 4) & Flash::kPgaerr);
  c.Write(kSr, 0xFFFF, 4);
  c.Write(kCr, 0, 4);
  // A write without PG.
  c.Write(a + 32, 1, 4);
  EXPECT_TRUE(c.Read(kSr, 4) & Flash::kPgserr);
  // With the error still set, the next erase does not start.
  c.Write(kCr, (1u << 1) | (2u << 3), 4);
  c.Write(kCr, c.Read(kCr, 4) | (1u << 16), 4);
  EXPECT_FALSE(c.Read(kSr, 4) & Flash::kBsy);
}

TEST(G474Flash, ReadingTheBusyBankStallsUntilTheEraseEnds) {
  VirtualChip c;
  Unlock(c);
  c.Write(kCr, (1u << 1) | (4u << 3), 4);
  c.Write(kCr, c.Read(kCr, 4) | (1u << 16), 4);
  const Picoseconds t0 = c.now();
  (void)c.Read(0x08000000, 4);  // same bank
  EXPECT_GT(c.now() - t0, Microseconds(20000));
  c.Write(kCr, (1u << 1) | (4u << 3), 4);
  c.Write(kCr, c.Read(kCr, 4) | (1u << 16), 4);
  const Picoseconds t1 = c.now();
  (void)c.Read(0x08040000, 4);  // the other bank: read-while-write
  EXPECT_LT(c.now() - t1, Microseconds(1));
}

TEST(G474Flash, PowerCutDuringProgramLeavesAMixAndResetsTheChip) {
  VirtualChip c;
  std::optional<ResetCause> cause;
  c.SetResetHandler([&](ResetCause rc) { cause = rc; });
  c.SetNmiHandler([] {});  // the cut double word reads with an ECC error
  Unlock(c);
  c.flash().CutPowerAfter(0, 42);
  c.Write(kCr, 1u, 4);
  c.Write(0x08002000, 0, 4);
  c.Write(0x08002004, 0, 4);
  c.AdvanceTo(c.now() + Microseconds(100));
  ASSERT_TRUE(cause);
  EXPECT_EQ(*cause, ResetCause::kPowerCut);
  const std::uint32_t lo = c.Read(0x08002000, 4), hi = c.Read(0x08002004, 4);
  EXPECT_NE(lo & hi, 0xFFFFFFFFu);           // some bits made it
  EXPECT_NE(lo | hi, 0u);                    // not all of them
  EXPECT_TRUE(c.Read(kCr, 4) & (1u << 31));  // locked again after the reset
}

TEST(G474Flash, ACutProgramReadsBackWithEccdAddressBankAndAnNmi) {
  VirtualChip c;
  std::optional<ResetCause> cause;
  c.SetResetHandler([&](ResetCause rc) { cause = rc; });
  int nmis = 0;
  std::uint32_t eccr_in_nmi = 0;
  c.SetNmiHandler([&] {
    ++nmis;
    eccr_in_nmi = c.Read(kEccr, 4);
  });
  Unlock(c);
  Program(c, 0x0807F000, 0x0123456789ABCDEFull);  // a good neighbour
  c.flash().CutPowerAfter(0, 7);
  c.Write(kCr, 1u, 4);
  c.Write(0x0807F008, 0x11111111u, 4);
  c.Write(0x0807F00C, 0x22222222u, 4);
  c.AdvanceTo(c.now() + Microseconds(100));
  ASSERT_TRUE(cause);
  EXPECT_EQ(c.Read(kEccr, 4), 0u) << "nothing read yet";
  EXPECT_EQ(c.Read(0x0807F000, 4), 0x89ABCDEFu);
  EXPECT_EQ(nmis, 0) << "the neighbour's ECC matches";
  (void)c.Read(0x0807F00C, 4);  // the high word of the cut double word
  EXPECT_EQ(nmis, 1);
  // Bank 2 (BK_ECC), the double word's offset in its bank (0x3F008), ECCD.
  EXPECT_EQ(eccr_in_nmi, kEccd | kBkEcc | 0x3F008u);
  EXPECT_EQ(*cause, ResetCause::kPowerCut) << "the NMI handler returned: no reset";
  // Every read raises the NMI again; the address stays the first error's until ECCD is
  // cleared (write 1).
  (void)c.Read(0x0807F008, 2);
  EXPECT_EQ(nmis, 2);
  c.Write(kEccr, kEccd, 4);
  EXPECT_EQ(c.Read(kEccr, 4) & kEccd, 0u);
  EXPECT_FALSE(c.violations().Contains("NVIC", "NMI"));
}

TEST(G474Flash, ACutEraseLeavesThePageCorruptUntilItIsErasedAgain) {
  VirtualChip c;
  c.SetResetHandler([](ResetCause) {});
  std::vector<std::uint32_t> seen;
  c.SetNmiHandler([&] {
    seen.push_back(c.Read(kEccr, 4));
    c.Write(kEccr, kEccd, 4);  // cleared: the next error gets its own address
  });
  Unlock(c);
  c.flash().CutPowerAfter(0, 9);
  c.Write(kCr, (1u << 1) | (5u << 3), 4);  // bank 1, page 5
  c.Write(kCr, c.Read(kCr, 4) | (1u << 16), 4);
  c.AdvanceTo(c.now() + Microseconds(30000));
  (void)c.Read(0x08000000 + 5 * 2048, 4);
  (void)c.Read(0x08000000 + 5 * 2048 + 2040, 4);
  (void)c.Read(0x08000000 + 6 * 2048, 4);  // the next page is whole
  ASSERT_EQ(seen.size(), 2u);
  EXPECT_EQ(seen[0], kEccd | (5u * 2048));
  EXPECT_EQ(seen[1], kEccd | (5u * 2048 + 2040));
  // A program of all zeros is accepted over a written double word and clears every
  // data and ECC bit: that double word reads again.
  Unlock(c);
  Program(c, 0x08000000 + 5 * 2048 + 8, 0);
  (void)c.Read(0x08000000 + 5 * 2048 + 8, 4);
  EXPECT_EQ(seen.size(), 2u);
  // Erasing the page again makes it whole.
  ErasePage(c, 5, false);
  for (std::uint32_t off = 0; off < 2048; off += 4) {
    EXPECT_EQ(c.Read(0x08000000 + 5 * 2048 + off, 4), 0xFFFFFFFFu);
  }
  EXPECT_EQ(seen.size(), 2u);
}

TEST(G474Flash, AnEccErrorWithNoNmiHandlerResetsTheChip) {
  // Both images' old vector tables sent the NMI to their fault handler, which resets:
  // at every start the same read, the same reset.
  VirtualChip c;
  std::vector<ResetCause> causes;
  c.SetResetHandler([&](ResetCause rc) { causes.push_back(rc); });
  Unlock(c);
  c.flash().CutPowerAfter(0, 3);
  Program(c, 0x08010000, 0x55);
  ASSERT_EQ(causes.size(), 1u);
  (void)c.Read(0x08010000, 4);
  ASSERT_EQ(causes.size(), 2u);
  EXPECT_EQ(causes[1], ResetCause::kSoftware);
  EXPECT_TRUE(c.violations().Contains("NVIC", "NMI"));
}

// A whole file's bytes (none when it cannot be read).
std::vector<char> ReadFile(const std::string& path) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  std::vector<char> bytes;
  if (f == nullptr) return bytes;
  char block[4096];
  for (std::size_t n; (n = std::fread(block, 1, sizeof block, f)) > 0;) {
    bytes.insert(bytes.end(), block, block + n);
  }
  std::fclose(f);
  return bytes;
}

TEST(G474Flash, ContentsPersistToAFile) {
  const std::string path =
      "/tmp/g474_flash_test_" + std::to_string(static_cast<long>(getpid())) + ".bin";
  std::remove(path.c_str());
  {
    ChipConfig cfg;
    cfg.flash.path = path;
    VirtualChip c(cfg);
    Unlock(c);
    Program(c, 0x0807F000, 0x0123456789ABCDEFull);
  }
  // The file itself: the whole array, erased but for the double-word, little-endian,
  // then the option bytes' 16-byte block.
  const std::vector<char> bytes = ReadFile(path);
  ASSERT_EQ(bytes.size(), Flash::kSize + 16);
  const unsigned char want[8] = {0xEF, 0xCD, 0xAB, 0x89, 0x67, 0x45, 0x23, 0x01};
  for (unsigned i = 0; i < 8; ++i) {
    EXPECT_EQ(static_cast<unsigned char>(bytes[0x7F000 + i]), want[i]) << i;
  }
  EXPECT_EQ(static_cast<unsigned char>(bytes[0x7F008]), 0xFF);
  EXPECT_EQ(static_cast<unsigned char>(bytes[0]), 0xFF);
  ChipConfig cfg;
  cfg.flash.path = path;
  VirtualChip c(cfg);
  EXPECT_TRUE(c.flash().mirrored());
  EXPECT_EQ(c.Read(0x0807F000, 4), 0x89ABCDEFu);
  std::remove(path.c_str());
  std::remove((path + ".ecc").c_str());
}

TEST(G474Flash, CorruptDoubleWordsPersistWithTheFile) {
  const std::string path =
      "/tmp/g474_flash_ecc_" + std::to_string(static_cast<long>(getpid())) + ".bin";
  std::remove(path.c_str());
  std::remove((path + ".ecc").c_str());
  {
    ChipConfig cfg;
    cfg.flash.path = path;
    VirtualChip c(cfg);
    c.SetResetHandler([](ResetCause) {});
    Unlock(c);
    c.flash().CutPowerAfter(0, 5);
    Program(c, 0x0807F800, 0x1234);
  }
  ChipConfig cfg;
  cfg.flash.path = path;
  VirtualChip c(cfg);
  int nmis = 0;
  c.SetNmiHandler([&] { ++nmis; });
  (void)c.Read(0x0807F800, 4);
  EXPECT_EQ(nmis, 1) << "the restarted board reads the cut double word as the chip would";
  std::remove(path.c_str());
  std::remove((path + ".ecc").c_str());
}

TEST(G474Flash, AFileOfAnotherSizeIsLeftAlone) {
  const std::string path =
      "/tmp/g474_flash_other_" + std::to_string(static_cast<long>(getpid())) + ".bin";
  std::ofstream(path, std::ios::binary) << std::string(4096, '\x00');
  {
    ChipConfig cfg;
    cfg.flash.path = path;
    VirtualChip c(cfg);
    EXPECT_FALSE(c.flash().mirrored());
    EXPECT_EQ(c.Read(0x0807F000, 4), 0xFFFFFFFFu);  // erased, not the file's zeros
    Unlock(c);
    Program(c, 0x0807F000, 0x0123456789ABCDEFull);
  }
  EXPECT_EQ(ReadFile(path), std::vector<char>(4096, '\x00'));
  std::remove(path.c_str());
}

}  // namespace
