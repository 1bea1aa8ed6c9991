// Flash in RAM with the STM32G4's rules, optionally mirrored to a file (so a restarted
// simulated board keeps what it stored), and with power cuts for tests: after a set
// number of operations the next one is interrupted — an interrupted erase leaves the
// page with random bytes, an interrupted program leaves the double-word with a random
// mix of its old and new bits — and every later operation fails until PowerOn().
//
// The file is written where each operation changed it (one page, or one double-word),
// right after the operation: a firmware update programs thousands of double-words, and
// rewriting a whole chip's 512 KB after each took minutes. A process killed at any
// moment (mjc sim under kill -9: a power cut) leaves the file as the operations that
// had returned left it — each write is one system call, which a kill cannot split.
#pragma once

#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "hal/flash.h"

namespace mjc::hal {

class SimFlash final : public Flash {
 public:
  // `pages` pages of erased flash. With a path, the contents are loaded from it when it
  // exists and written back after every operation; a new file is created whole (every
  // byte erased). A file of another size is left untouched and not mirrored (the flash
  // starts erased), with the reason in *why.
  // A copy holds the same contents in memory only: it never writes the file.
  explicit SimFlash(std::uint32_t pages, std::string path = {},
                    std::string* why = nullptr);

  // True when a path was given and its file is being kept up to date.
  bool mirrored() const { return file_.fd >= 0; }
  // Writes to the file that failed (a full disk); the contents in memory are right.
  long file_errors() const { return file_errors_; }

  // Interrupts the (count+1)-th operation from now; -1 disables. The seed makes the
  // garbage reproducible.
  void CutPowerAfter(long count, std::uint64_t seed);
  // Restores power (a reboot); the contents are what the cut left.
  void PowerOn() {
    powered_ = true;
    cut_after_ = -1;
  }
  long operations() const { return operations_; }
  // Reads (and pre-program checks) that found an ECC double error so far.
  long ecc_errors() const { return ecc_errors_; }
  // Double words whose data and ECC do not match now.
  long corrupt_double_words() const;

 private:
  FlashResult DoErasePage(std::uint32_t page) override;
  FlashResult DoProgram(std::uint32_t page, std::uint32_t offset,
                        std::uint64_t value) override;
  FlashResult DoRead(std::uint32_t page, std::uint32_t offset,
                     std::span<std::uint8_t> out) const override;
  std::uint32_t DoPageCount() const override { return pages_; }
  // True when this operation is the one the power cut interrupts.
  bool Interrupted();
  // Writes memory [offset, offset + bytes) to the file, when there is one.
  void Save(std::size_t offset, std::size_t bytes);
  // Marks the double words of [offset, offset + bytes); the ECC file follows.
  void SetEcc(std::size_t offset, std::size_t bytes, bool corrupt);
  void SaveEcc();
  bool AnyCorrupt(std::size_t offset, std::size_t bytes) const;

  // The mirror file, open for writing: closed with its owner, moved with it, never
  // copied (a copy of the flash is memory only).
  struct MirrorFile {
    int fd = -1;
    MirrorFile() = default;
    ~MirrorFile();
    MirrorFile(const MirrorFile&) {}
    MirrorFile& operator=(const MirrorFile& other);
    MirrorFile(MirrorFile&& other) noexcept;
    MirrorFile& operator=(MirrorFile&& other) noexcept;
  };

  std::uint32_t pages_;
  std::vector<std::uint8_t> memory_;
  MirrorFile file_;
  MirrorFile ecc_file_;        // "<path>.ecc"
  std::vector<bool> ecc_bad_;  // per double word: data and ECC do not match
  mutable long ecc_errors_ = 0;
  long file_errors_ = 0;
  bool powered_ = true;
  long cut_after_ = -1;
  long operations_ = 0;
  std::mt19937_64 rng_;
};

}  // namespace mjc::hal
