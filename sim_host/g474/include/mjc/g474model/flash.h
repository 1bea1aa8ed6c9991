// The STM32G474's embedded flash: the FLASH register block (0x40022000) and the
// memory-mapped array (512 KB at 0x08000000), from RM0440 §5 "Embedded Flash memory
// (FLASH)"; offsets, fields and reset values from ST's SVD v2.9.
//
// Covered:
//  - ACR: LATENCY (the chip checks it against HCLK, see ClockRules), PRFTEN, ICEN,
//    DCEN, ICRST/DCRST (only while the cache is off).
//  - KEYR: KEY1 = 0x45670123 then KEY2 = 0xCDEF89AB clear CR.LOCK; any other value or
//    order is a bus error and locks CR until the next reset (§5.3.5 "Flash memory
//    unlock"). OPTKEYR likewise for OPTLOCK.
//  - SR: EOP (set at the end of an operation only when CR.EOPIE = 1), OPERR (with
//    ERRIE), PROGERR, WRPERR, PGAERR, SIZERR, PGSERR, MISSERR, FASTERR, RDERR, OPTVERR,
//    all write-1-to-clear; BSY.
//  - CR: page erase (PER, PNB, BKER, STRT), bank mass erase (MER1/MER2), double-word
//    programming (PG: two 32-bit writes, the first 8-byte aligned, the second at +4
//    starts the operation) with the §5.3.8 error rules: a half-word write is SIZERR; a
//    first word not 8-aligned or a second word elsewhere is PGAERR; a double word that is
//    not erased is PROGERR unless the new value is all zeros; a write to the array
//    without PG, or starting while an earlier error flag is still set, is PGSERR; a write
//    or erase inside an active WRP area is WRPERR. An operation never starts with an
//    error. CR is ignored while locked; a write while BSY stalls the bus until BSY
//    clears, and so does a read of the bank being programmed (dual-bank read-while-
//    write only across banks).
//  - Busy times from DS12288 "Flash memory characteristics" (typical, from memory):
//    64-bit program 81.7 µs, page erase 22.02 ms, bank mass erase 22.13 ms.
//  - The array: dual bank (OPTR.DBANK = 1, the factory value 0xFFEFF8AA), 2 × 128 pages
//    of 2 KB; bank 2 at 0x08040000. Reads of 2 or 4 bytes. Flash size (0x1FFF75E0) and
//    the unique ID (0x1FFF7590) read as the chip's.
//  - Power cuts like hal::SimFlash: the (n+1)-th operation from now is interrupted at a
//    random point of its busy time (seeded); an interrupted erase leaves the page
//    random bytes, an interrupted program a random mix of old and new bits, and the
//    whole chip loses power (the owner restarts it). Optional persistence to a file.
//  - ECC (§5.3 "Error code correction (ECC)", FLASH_ECCR): the array stores 8 ECC
//    bits with every 64-bit double word, written with it by a program and set to the
//    erased pattern's by an erase. An operation cut by a power loss leaves data and
//    ECC that do not match: every double word of a cut erase and the double word of a
//    cut program read back with a double error. Such a read (a CPU or debugger load;
//    not the interface's own erased-check before programming) sets ECCR.ECCD with
//    ADDR_ECC (the double word's byte offset in its bank) and BK_ECC (its bank) — both
//    kept from the first error until ECCD and ECCC are cleared (write 1) — and raises
//    the NMI (TakeNmi; the chip takes it, it cannot be masked). An erase of the page,
//    or a program of all zeros over the double word (the one value the interface
//    accepts over a written double word), leaves it consistent again. The corrupt
//    double words persist with the array (a second file, "<path>.ecc", a bit each).
//
//  - Option bytes: FLASH_OPTR, OPTSTRT and OBL_LAUNCH through OptionBytes
//    (option_bytes.h), its word kept after the array in the persistence file.
//
// Not covered: fast programming (FSTPG), PCROP and the securable area, single-bit
// (corrected) ECC errors (ECCC and its FLASH interrupt: a cut never leaves one here), ECC
// errors in the system memory (SYSF_ECC), single-bank mode (DBANK = 0), power-down modes,
// the OTP area.
#pragma once

#include <cstdint>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "mjc/g474model/common.h"
#include "mjc/g474model/option_bytes.h"
#include "mjc/g474model/register_table.h"

namespace mjc::g474model {

struct FlashConfig {
  // Persistence file ("" = none): loaded when its size is the array's, and kept up to
  // date after every erase and program — the page or double-word it changed, one write
  // each, so a process killed at any moment leaves the file as the operations that had
  // completed left it. After the array, a 16-byte block keeps the option bytes
  // (OptionBytes); a file of the array alone is taken with factory options and gets the
  // block. A missing file is created erased; a file of another size is left untouched
  // and not kept (the array starts erased).
  std::string path;
  Picoseconds program_time = Microseconds(81.7);
  Picoseconds page_erase_time = Microseconds(22020);
  Picoseconds mass_erase_time = Microseconds(22130);
  // OPTSTRT to BSY cleared: the option page's erase and its words programmed (assumed
  // a page erase and eight double words; DS12288 gives no separate figure we hold).
  Picoseconds option_program_time = Microseconds(22020 + 8 * 81.7);
  std::uint32_t uid[3] = {0x00400031u, 0x4E4B5003u, 0x20343736u};
};

class Flash final : public Peripheral {
 public:
  static constexpr std::uint32_t kBase = 0x40022000;       // registers
  static constexpr std::uint32_t kArrayBase = 0x08000000;  // memory
  static constexpr std::uint32_t kPageSize = 2048;
  static constexpr std::uint32_t kPagesPerBank = 128;
  static constexpr std::uint32_t kSize = 2 * kPagesPerBank * kPageSize;  // 512 KB
  static constexpr std::uint32_t kKey1 = 0x45670123u, kKey2 = 0xCDEF89ABu;
  static constexpr std::uint32_t kOptKey1 = 0x08192A3Bu, kOptKey2 = 0x4C5D6E7Fu;

  // SR bits.
  static constexpr std::uint32_t kEop = 1u << 0, kOperr = 1u << 1, kProgerr = 1u << 3,
                                 kWrperr = 1u << 4, kPgaerr = 1u << 5, kSizerr = 1u << 6,
                                 kPgserr = 1u << 7, kMisserr = 1u << 8,
                                 kFasterr = 1u << 9, kRderr = 1u << 14,
                                 kOptverr = 1u << 15, kBsy = 1u << 16;
  // ECCR bits (CMSIS FLASH_ECCR_*): ADDR_ECC 18:0, BK_ECC 21, SYSF_ECC 22, ECCCIE 24,
  // ECCC 30 and ECCD 31 (both write 1 to clear).
  static constexpr std::uint32_t kEccAddrMask = 0x7FFFFu, kBkEcc = 1u << 21,
                                 kSysfEcc = 1u << 22, kEcccie = 1u << 24,
                                 kEccc = 1u << 30, kEccd = 1u << 31;

  Flash(ViolationLog* log, FlashConfig config);
  ~Flash() override;
  Flash(const Flash&) = delete;
  Flash& operator=(const Flash&) = delete;

  // The register block.
  bool Read(const Access& a, std::uint32_t* value) override;
  bool Write(const Access& a) override;
  // A system reset: registers to reset values (locked); an operation in progress
  // completes first (the reset waits for it, as the chip's flash interface does).
  void Reset() override;
  void Advance(Picoseconds now) override;
  Picoseconds NextEvent() const override;

  // The array and the information block, addressed by bus address.
  bool ReadMemory(std::uint32_t address, unsigned bytes, std::uint32_t* value);
  bool WriteMemory(std::uint32_t address, std::uint32_t value, unsigned bytes);
  static bool InArray(std::uint32_t a) {
    return a >= kArrayBase && a < kArrayBase + kSize;
  }
  static bool InInfo(std::uint32_t a) {
    return (a >= 0x1FFF7590u && a < 0x1FFF759Cu) || (a >= 0x1FFF75E0u && a < 0x1FFF75E4u);
  }
  // Set by an array access that had to wait for the busy bank: the time the access
  // completes. The chip moves its clock there. 0 when no stall.
  Picoseconds TakeStall() {
    const Picoseconds s = stall_until_;
    stall_until_ = 0;
    return s;
  }

  // True when a persistence file was given and is being kept up to date.
  bool mirrored() const { return file_ >= 0; }
  std::uint32_t latency() const { return acr_ & 0xFu; }
  bool busy() const { return op_.kind != OpKind::kNone; }
  bool locked() const { return (cr_ & (1u << 31)) != 0; }
  std::uint32_t sr() const { return sr_; }
  // FLASH interrupt line (IRQ 4): EOP with EOPIE or OPERR with ERRIE.
  bool irq() const {
    return ((sr_ & kEop) && (cr_ & (1u << 24))) || ((sr_ & kOperr) && (cr_ & (1u << 25)));
  }

  // ECC: true once for each read that found a double error (the NMI the chip takes).
  bool TakeNmi() {
    const bool n = nmi_;
    nmi_ = false;
    return n;
  }
  std::uint32_t eccr() const { return eccr_; }
  std::uint32_t acr() const { return acr_; }
  // Whether the double word at array offset `offset` would read with a double error.
  bool EccCorrupt(std::uint32_t offset) const { return ecc_bad_[offset / 8]; }
  // Double words that read with a double error now, and reads that found one so far.
  long corrupt_double_words() const;
  long ecc_detections() const { return ecc_detections_; }

  // Power cuts: the (count+1)-th erase or program from now is interrupted; -1 disables.
  void CutPowerAfter(long count, std::uint64_t seed);
  long operations() const { return operations_; }
  // Called when an interrupted operation takes the power away (the chip power-cycles).
  void SetPowerCutHook(std::function<void()> hook) { power_cut_hook_ = std::move(hook); }
  // The supply fails now (from the world): an operation in progress is left as a cut
  // leaves it. Returns true when one was.
  bool PowerLost();
  // Direct view of the array for tests and the world (offset from 0x08000000).
  const std::vector<std::uint8_t>& contents() const { return memory_; }
  std::vector<std::uint8_t>& mutable_contents() { return memory_; }
  // The user option bytes (FLASH_OPTR; option_bytes.h).
  OptionBytes& options() { return options_; }
  const OptionBytes& options() const { return options_; }

 private:
  // The registers without code of their own (register_table.h).
  static RegisterTable<Flash> Registers();
  // WRP1AR, WRP1BR, WRP2AR, WRP2BR at `offset`, or null.
  const std::uint32_t* Wrp(std::uint32_t offset) const;
  enum class OpKind { kNone, kErase, kProgram };
  struct Operation {
    OpKind kind = OpKind::kNone;
    std::uint32_t offset = 0;  // into the array
    std::uint32_t length = 0;
    std::uint64_t value = 0;  // program
    Picoseconds end = 0;
    Picoseconds cut_at = kNever;  // when a scheduled power cut interrupts it
  };
  void Error(std::uint32_t flags, const std::string& why);
  bool ErrorsPending() const;
  bool WriteProtected(std::uint32_t offset) const;
  void StartOperation(Operation op, Picoseconds duration);
  void Complete();
  void Interrupt();
  int BankOf(std::uint32_t offset) const { return offset < kSize / 2 ? 0 : 1; }
  // Writes array bytes [offset, offset + bytes) to the persistence file, if kept.
  void Save(std::uint32_t offset, std::uint32_t bytes) const;
  // Marks the double words of [offset, offset + bytes) consistent or not; the ECC file
  // is rewritten when one changed.
  void SetEcc(std::uint32_t offset, std::uint32_t bytes, bool corrupt);
  void SaveEcc() const;

  ViolationLog* log_;
  FlashConfig config_;
  Picoseconds now_ = 0;
  std::vector<std::uint8_t> memory_;
  int file_ = -1;              // the persistence file, open for writing; -1: none
  int ecc_file_ = -1;          // "<path>.ecc": a bit per double word, 1 = corrupt
  std::vector<bool> ecc_bad_;  // per double word: data and ECC do not match
  std::uint32_t eccr_ = 0;
  bool nmi_ = false;
  long ecc_detections_ = 0;
  std::uint32_t acr_ = 0, sr_ = 0, cr_ = 0;
  std::uint32_t wrp_[4] = {};  // WRP1AR, WRP1BR, WRP2AR, WRP2BR
  int key_stage_ = 0;          // 1 after KEY1
  bool keys_dead_ = false;     // a wrong key: locked until reset
  int optkey_stage_ = 0;
  // PG: the first word of a double word waiting for its second.
  bool have_first_ = false;
  std::uint32_t first_offset_ = 0, first_word_ = 0;
  Operation op_;
  Picoseconds stall_until_ = 0;
  long cut_after_ = -1;
  long operations_ = 0;
  std::mt19937_64 rng_;
  std::function<void()> power_cut_hook_;
  OptionBytes options_;
};

}  // namespace mjc::g474model
