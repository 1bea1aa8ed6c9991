// The simulated flash against the STM32G4's rules as hal/flash.h states them from
// RM0440 §5 (2 KB pages, erase to 0xFF, 64-bit programs at 8-aligned offsets only into
// erased double-words, little-endian), its file, and its power cuts: the cut operation
// fails and leaves garbage of the documented kind, every later one fails until PowerOn,
// and the double words it left read as ECC double errors (RM0440 §5.3: data and ECC
// bits cut together no longer match) until the page is erased again.
#include "hal/sim/sim_flash.h"

#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

namespace {

using mjc::hal::FlashResult;
using mjc::hal::SimFlash;

std::array<std::uint8_t, 8> DoubleWord(const SimFlash& flash, std::uint32_t page,
                                       std::uint32_t offset) {
  std::array<std::uint8_t, 8> dw{};
  EXPECT_EQ(flash.Read(page, offset, dw), FlashResult::kOk);
  return dw;
}

// The double word's bytes as they are, whatever the read answers.
std::array<std::uint8_t, 8> RawDoubleWord(const SimFlash& flash, std::uint32_t page,
                                          std::uint32_t offset) {
  std::array<std::uint8_t, 8> dw{};
  (void)flash.Read(page, offset, dw);
  return dw;
}

std::uint64_t Value(const std::array<std::uint8_t, 8>& dw) {
  std::uint64_t v = 0;
  for (int i = 7; i >= 0; --i) v = (v << 8) | dw[static_cast<std::size_t>(i)];
  return v;
}

bool PageErased(const SimFlash& flash, std::uint32_t page) {
  std::array<std::uint8_t, SimFlash::kPageSize> bytes{};
  EXPECT_EQ(flash.Read(page, 0, bytes), FlashResult::kOk);
  for (const std::uint8_t b : bytes) {
    if (b != 0xFF) return false;
  }
  return true;
}

TEST(SimFlash, FollowsTheG4Rules) {
  SimFlash flash(2);
  EXPECT_EQ(flash.page_count(), 2u);
  EXPECT_TRUE(PageErased(flash, 0));
  EXPECT_TRUE(PageErased(flash, 1));
  EXPECT_EQ(flash.ProgramDoubleWord(0, 4, 1),
            FlashResult::kBadAddress);  // unaligned
  EXPECT_EQ(flash.ProgramDoubleWord(2, 0, 1),
            FlashResult::kBadAddress);  // no page 2
  EXPECT_EQ(flash.ProgramDoubleWord(0, 2048, 1),
            FlashResult::kBadAddress);  // past the page's end
  EXPECT_EQ(flash.ErasePage(2), FlashResult::kBadAddress);
  EXPECT_EQ(flash.ProgramDoubleWord(0, 0, 1), FlashResult::kOk);
  EXPECT_EQ(flash.ProgramDoubleWord(0, 0, 0), FlashResult::kNotErased);  // twice
  EXPECT_EQ(flash.ErasePage(0), FlashResult::kOk);
  EXPECT_TRUE(PageErased(flash, 0));
  EXPECT_EQ(flash.ProgramDoubleWord(0, 0, 0), FlashResult::kOk);
}

TEST(SimFlash, ProgramsLittleEndianAndReadsAnySpan) {
  SimFlash flash(2);
  ASSERT_EQ(flash.ProgramDoubleWord(1, 2040, 0x0807060504030201u), FlashResult::kOk);
  const std::array<std::uint8_t, 8> expected = {1, 2, 3, 4, 5, 6, 7, 8};
  EXPECT_EQ(DoubleWord(flash, 1, 2040), expected);
  std::array<std::uint8_t, 3> middle{};
  ASSERT_EQ(flash.Read(1, 2043, middle), FlashResult::kOk);
  EXPECT_EQ(middle, (std::array<std::uint8_t, 3>{4, 5, 6}));
  std::array<std::uint8_t, 9> past_end{};
  EXPECT_EQ(flash.Read(1, 2040, past_end), FlashResult::kBadAddress);
  EXPECT_EQ(flash.Read(2, 0, middle), FlashResult::kBadAddress);
  // Other pages and double-words untouched.
  EXPECT_TRUE(PageErased(flash, 0));
  EXPECT_EQ(Value(DoubleWord(flash, 1, 2032)), ~std::uint64_t{0});
}

TEST(SimFlash, PersistsToItsFile) {
  const std::string path = ::testing::TempDir() + "/mjc_sim_flash_test.bin";
  std::remove(path.c_str());
  {
    SimFlash flash(4, path);
    ASSERT_EQ(flash.ProgramDoubleWord(3, 16, 0x1122334455667788u), FlashResult::kOk);
  }
  {
    std::ifstream in(path, std::ios::binary | std::ios::ate);
    EXPECT_EQ(static_cast<long>(in.tellg()), 4 * 2048);
  }
  std::string why;
  SimFlash again(4, path, &why);  // a restarted board
  EXPECT_EQ(why, "");
  EXPECT_EQ(Value(DoubleWord(again, 3, 16)), 0x1122334455667788u);
  EXPECT_EQ(again.ProgramDoubleWord(3, 16, 0), FlashResult::kNotErased);

  // A file of another size is not this flash: erased flash, and the reason.
  SimFlash other(8, path, &why);
  EXPECT_NE(why.find("8192 bytes, not 16384"), std::string::npos) << why;
  EXPECT_TRUE(PageErased(other, 3));
  std::remove(path.c_str());
}

TEST(SimFlash, APowerCutInterruptsTheChosenOperationAndEveryLaterOne) {
  SimFlash flash(2);
  flash.CutPowerAfter(2, 1);
  EXPECT_EQ(flash.ProgramDoubleWord(0, 0, 0), FlashResult::kOk);
  EXPECT_EQ(flash.ProgramDoubleWord(0, 8, 0), FlashResult::kOk);
  EXPECT_EQ(flash.ProgramDoubleWord(0, 16, 0), FlashResult::kHardwareError);  // the 3rd
  EXPECT_EQ(flash.ProgramDoubleWord(0, 24, 0), FlashResult::kHardwareError);
  EXPECT_EQ(flash.ErasePage(1), FlashResult::kHardwareError);
  EXPECT_EQ(Value(DoubleWord(flash, 0, 0)), 0u);                  // reads still work
  EXPECT_EQ(Value(DoubleWord(flash, 0, 24)), ~std::uint64_t{0});  // nothing written
  EXPECT_EQ(flash.operations(), 3);
  flash.PowerOn();
  EXPECT_EQ(flash.ProgramDoubleWord(0, 24, 0), FlashResult::kOk);
  EXPECT_EQ(flash.ErasePage(1), FlashResult::kOk);  // no cut pending any more
  EXPECT_EQ(flash.operations(), 5);
}

TEST(SimFlash, AnInterruptedProgramLeavesAMixOfOldAndNewBits) {
  // Programming can only clear bits: of an erased double-word cut while written, the
  // bits the new value keeps at 1 stay 1, and its 0 bits are each 0 or still 1.
  constexpr std::uint64_t kNew = 0x00FF'0F0F'3C3C'A5A5u;
  SimFlash flash(1);
  flash.CutPowerAfter(0, 7);
  ASSERT_EQ(flash.ProgramDoubleWord(0, 8, kNew), FlashResult::kHardwareError);
  const std::uint64_t left = Value(RawDoubleWord(flash, 0, 8));
  EXPECT_EQ(left & kNew, kNew);
  EXPECT_NE(left, kNew);               // 32 bits each had to make it
  EXPECT_NE(left, ~std::uint64_t{0});  // and none at all is as unlikely
  // The same seed, the same garbage (reproducible failures).
  SimFlash twin(1);
  twin.CutPowerAfter(0, 7);
  ASSERT_EQ(twin.ProgramDoubleWord(0, 8, kNew), FlashResult::kHardwareError);
  EXPECT_EQ(Value(RawDoubleWord(twin, 0, 8)), left);
  // Its ECC does not match: every read of it fails (an NMI on the chip), a read of its
  // neighbours does not, and it cannot be programmed (the erased-check reads it).
  std::array<std::uint8_t, 8> dw{};
  EXPECT_EQ(flash.Read(0, 8, dw), FlashResult::kHardwareError);
  EXPECT_EQ(flash.Read(0, 12, std::span(dw).first(1)), FlashResult::kHardwareError);
  EXPECT_EQ(flash.Read(0, 0, dw), FlashResult::kOk);
  EXPECT_EQ(flash.Read(0, 16, dw), FlashResult::kOk);
  EXPECT_EQ(flash.corrupt_double_words(), 1);
  flash.PowerOn();
  EXPECT_EQ(flash.ProgramDoubleWord(0, 8, kNew), FlashResult::kHardwareError);
  EXPECT_EQ(flash.ecc_errors(), 4);  // the raw read, two reads, the program
  ASSERT_EQ(flash.ErasePage(0), FlashResult::kOk);
  EXPECT_EQ(flash.corrupt_double_words(), 0);
  EXPECT_EQ(flash.ProgramDoubleWord(0, 8, kNew), FlashResult::kOk);
}

TEST(SimFlash, AnInterruptedEraseLeavesThePageNeitherOldNorErased) {
  SimFlash flash(1);
  ASSERT_EQ(flash.ProgramDoubleWord(0, 0, 0), FlashResult::kOk);
  flash.CutPowerAfter(0, 3);
  ASSERT_EQ(flash.ErasePage(0), FlashResult::kHardwareError);
  flash.PowerOn();
  std::array<std::uint8_t, SimFlash::kPageSize> bytes{};
  // Every double word of the cut page reads as an ECC error.
  ASSERT_EQ(flash.Read(0, 0, bytes), FlashResult::kHardwareError);
  EXPECT_EQ(flash.corrupt_double_words(), 256);
  int distinct = 0;
  std::array<bool, 256> seen{};
  for (const std::uint8_t b : bytes) {
    if (!seen[b]) ++distinct;
    seen[b] = true;
  }
  EXPECT_GT(distinct, 200);  // random bytes, not a pattern the old page or erase leaves
  EXPECT_EQ(flash.ErasePage(0), FlashResult::kOk);  // a whole erase repairs it
  EXPECT_TRUE(PageErased(flash, 0));
}

std::vector<std::uint8_t> FileBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::vector<std::uint8_t> out;
  for (int c; (c = in.get()) != EOF;) out.push_back(static_cast<std::uint8_t>(c));
  return out;
}

TEST(SimFlash, WritesEachOperationWhereItChangedTheFile) {
  const std::string path = ::testing::TempDir() + "/mjc_flash_ops.bin";
  std::remove(path.c_str());
  {
    SimFlash flash(4, path);
    EXPECT_TRUE(flash.mirrored());
    // A new file is the whole flash, erased, at once.
    EXPECT_EQ(FileBytes(path), std::vector<std::uint8_t>(4 * 2048, 0xFF));
    // Bytes changed behind its back (page 3) stay as they are: a program of page 1
    // writes its own double-word only, an erase of page 2 its own page only.
    {
      std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
      f.seekp(3 * 2048 + 5);
      f.put(0x42);
    }
    ASSERT_EQ(flash.ProgramDoubleWord(1, 16, 0x0123456789ABCDEFull), FlashResult::kOk);
    ASSERT_EQ(flash.ErasePage(2), FlashResult::kOk);
    const auto bytes = FileBytes(path);
    ASSERT_EQ(bytes.size(), 4u * 2048);
    EXPECT_EQ(bytes[3 * 2048 + 5], 0x42);
    EXPECT_EQ(bytes[2048 + 16], 0xEF);
    EXPECT_EQ(bytes[2048 + 23], 0x01);
    EXPECT_EQ(flash.file_errors(), 0);
  }
  std::remove(path.c_str());
}

TEST(SimFlash, CorruptDoubleWordsPersistBesideTheFile) {
  const std::string path = ::testing::TempDir() + "/mjc_flash_ecc.bin";
  std::remove(path.c_str());
  std::remove((path + ".ecc").c_str());
  {
    SimFlash flash(4, path);
    flash.CutPowerAfter(0, 11);
    ASSERT_EQ(flash.ProgramDoubleWord(2, 40, 0x55), FlashResult::kHardwareError);
  }  // the process dies (kill -9 keeps what was written)
  SimFlash again(4, path);
  ASSERT_TRUE(again.mirrored());
  std::array<std::uint8_t, 8> dw{};
  EXPECT_EQ(again.Read(2, 40, dw), FlashResult::kHardwareError);
  EXPECT_EQ(again.Read(2, 32, dw), FlashResult::kOk);
  ASSERT_EQ(again.ErasePage(2), FlashResult::kOk);
  SimFlash third(4, path);
  EXPECT_EQ(third.Read(2, 40, dw), FlashResult::kOk);
  std::remove(path.c_str());
  std::remove((path + ".ecc").c_str());
}

TEST(SimFlash, AFileOfAnotherSizeIsLeftUntouched) {
  const std::string path = ::testing::TempDir() + "/mjc_flash_other.bin";
  std::vector<std::uint8_t> other(3000, 0x5A);
  std::ofstream(path, std::ios::binary)
      .write(reinterpret_cast<const char*>(other.data()),
             static_cast<std::streamsize>(other.size()));
  std::string why;
  SimFlash flash(2, path, &why);
  EXPECT_FALSE(flash.mirrored());
  EXPECT_EQ(why, path + " holds 3000 bytes, not 4096: left untouched");
  ASSERT_EQ(flash.ErasePage(0), FlashResult::kOk);
  ASSERT_EQ(flash.ProgramDoubleWord(0, 0, 7), FlashResult::kOk);
  EXPECT_EQ(FileBytes(path), other);
  std::remove(path.c_str());
}

}  // namespace
