// The STM32G474's user option bytes behind FLASH_OPTR (RM0440 §5.4 "FLASH option
// bytes", FLASH_OPTR; bit positions from ST's SVD v2.9) and the boot decision they take
// part in (RM0440 §2.6 "Boot configuration").
//
// Three copies of the option word, as the chip has them:
//  - stored: the option bytes in flash (kept across resets and power cuts, and in the
//    flash model's persistence file), each word beside its complement;
//  - loaded: what the chip runs with, copied from the stored word by the option-byte
//    loader at a power-on reset and at OBL_LAUNCH — and only then: a system reset
//    (software, watchdog) keeps the loaded value;
//  - the FLASH_OPTR register: the loaded value after every reset; software writes it
//    (only while FLASH_CR.OPTLOCK = 0) and FLASH_CR.OPTSTRT copies it into the stored
//    word (erase and program of the option page: BSY for `program_time`).
// So a new value takes effect only after OBL_LAUNCH (which resets the chip, RCC_CSR
// OBLRSTF) or a power-on. OPTSTRT and OBL_LAUNCH are ignored while OPTLOCK = 1 (RM0440
// FLASH_CR: "can only be written when OPTLOCK is cleared"); OPTSTRT is also refused
// while an array operation is busy. A power cut while the option page is being written
// leaves the word and its complement disagreeing: the next load sets FLASH_SR.OPTVERR
// (again after each system reset, until a load succeeds) and the chip runs with the
// factory word (the model's choice; RM0440 gives no defaults we hold a copy of).
//
// The boot decision (RM0440 §2.6, Table "Boot modes"): BOOT0 is the PB8-BOOT0 pin when
// nSWBOOT0 (bit 26) = 1, else the complement of nBOOT0 (bit 27). BOOT0 = 0 boots main
// flash; BOOT0 = 1 boots system memory (ST's ROM bootloader) when nBOOT1 (bit 23) = 1,
// embedded SRAM when nBOOT1 = 0. A floating PB8 reads a different level at every start
// (ST's answer on its community forum); the chip draws it from a seeded generator.
//
// Not covered: RDP levels and readout protection, the PCROP/WRP/securable-area option
// registers (they keep the flash model's factory values), BOR level, the IWDG/WWDG
// hardware modes, nRST_* and NRST_MODE, SRAM parity, the dual-bank boot of BFB2 and the
// single-bank organisation (DBANK = 0): both are reported when loaded.
#pragma once

#include <cstdint>
#include <functional>
#include <random>

#include "mjc/g474model/common.h"

namespace mjc::g474model {

enum class BootSource : std::uint8_t { kMainFlash, kSystemMemory, kSram };
const char* BootSourceName(BootSource s);

// RM0440 §2.6: where the chip boots with option word `optr` and BOOT0 pin level `pin`.
BootSource BootFrom(std::uint32_t optr, bool pin);

class OptionBytes {
 public:
  static constexpr std::uint32_t kOffset = 0x20;  // FLASH_OPTR
  // From the factory (RM0440 FLASH_OPTR): RDP level 0 (0xAA), DBANK = 1, nSWBOOT0 = 1
  // (BOOT0 from PB8), nBOOT0 = 1, nBOOT1 = 1, BFB2 = 0.
  static constexpr std::uint32_t kFactory = 0xFFEFF8AAu;
  // The bits FLASH_OPTR holds (SVD: RDP 7:0, BOR_LEV 10:8, nRST_STOP/STDBY/SHDW 14:12,
  // IWDG_SW/STOP/STDBY 18:16, WWDG_SW 19, BFB2 20, DBANK 22, nBOOT1 23, SRAM_PE 24,
  // CCMSRAM_RST 25, nSWBOOT0 26, nBOOT0 27, NRST_MODE 29:28, IRHEN 30); the reserved
  // bits 11, 15, 21 and 31 read 1.
  static constexpr std::uint32_t kWritable = 0x7FDF77FFu;
  static constexpr std::uint32_t kBfb2 = 1u << 20, kDbank = 1u << 22, kNBoot1 = 1u << 23,
                                 kNSwBoot0 = 1u << 26, kNBoot0 = 1u << 27;
  // Bytes the stored option word takes in the persistence file.
  static constexpr std::uint32_t kFileBytes = 16;

  OptionBytes(ViolationLog* log, Picoseconds program_time);

  // The persistence file: the stored word from a block `Persist` wrote (a block of
  // another kind, e.g. an older file without one, leaves the factory word), then
  // loaded as at a power-on.
  void Restore(const std::uint8_t* block, std::uint32_t bytes);
  // Keeps the stored word at `offset` of the open file `fd` (written now and after
  // every change); fd < 0: none.
  void Persist(int fd, std::uint32_t offset);

  // FLASH_OPTR as software reads it.
  std::uint32_t reg() const { return reg_; }
  // What the chip runs with.
  std::uint32_t loaded() const { return loaded_; }
  // The option page in flash (its word; meaningless when !stored_valid()).
  std::uint32_t stored() const { return stored_; }
  bool stored_valid() const { return stored_ == ~stored_complement_; }
  // The last load found the stored word broken (FLASH_SR.OPTVERR).
  bool load_error() const { return load_error_; }
  bool busy() const { return end_ != kNever; }

  // A write to FLASH_OPTR (`a`), with CR's OPTLOCK as it is now.
  void Write(const Access& a, bool optlock, Picoseconds now);
  // FLASH_CR.OPTSTRT set; `array_busy`: an erase or program is running.
  void Start(bool optlock, bool array_busy, Picoseconds now);
  // FLASH_CR.OBL_LAUNCH set: asks for the option-byte loading reset (the hook).
  void Launch(bool optlock, Picoseconds now);
  void SetLaunchHook(std::function<void()> hook) { launch_hook_ = std::move(hook); }

  void Advance(Picoseconds now);
  Picoseconds NextEvent() const { return end_; }
  // A system reset: a programming in progress completes first (as the flash's own
  // operations do), the register shows the loaded word again.
  void Reset();
  // The option-byte loader (power-on reset, OBL_LAUNCH): loaded = stored when the word
  // and its complement agree; else OPTVERR and the factory word.
  void Load(Picoseconds now);
  // The supply fails: a programming in progress leaves a broken stored word. True when
  // one was.
  bool PowerLost();

 private:
  void Complete();
  void Save() const;

  ViolationLog* log_;
  Picoseconds program_time_;
  std::uint32_t stored_ = kFactory, stored_complement_ = ~kFactory;
  std::uint32_t loaded_ = kFactory, reg_ = kFactory;
  std::uint32_t pending_ = 0;  // what OPTSTRT is writing
  Picoseconds end_ = kNever;
  bool load_error_ = false;
  int fd_ = -1;
  std::uint32_t file_offset_ = 0;
  std::mt19937_64 rng_{0x0B7E5u};
  std::function<void()> launch_hook_;
};

}  // namespace mjc::g474model
