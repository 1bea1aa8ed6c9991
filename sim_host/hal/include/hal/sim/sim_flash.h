// Flash in RAM with the STM32G4's rules, optionally mirrored to a file (so a restarted
// simulated board keeps what it stored), and with power cuts for tests: after a set
// number of operations the next one is interrupted — an interrupted erase leaves the
// page with random bytes, an interrupted program leaves the double-word with a random
// mix of its old and new bits — and every later operation fails until PowerOn().
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
  // exists (a file of another size is ignored with a reason in *why) and written back
  // after every operation.
  explicit SimFlash(std::uint32_t pages, std::string path = {},
                    std::string* why = nullptr);

  // Interrupts the (count+1)-th operation from now; -1 disables. The seed makes the
  // garbage reproducible.
  void CutPowerAfter(long count, std::uint64_t seed);
  // Restores power (a reboot); the contents are what the cut left.
  void PowerOn() {
    powered_ = true;
    cut_after_ = -1;
  }
  long operations() const { return operations_; }

 private:
  FlashResult DoErasePage(std::uint32_t page) override;
  FlashResult DoProgram(std::uint32_t page, std::uint32_t offset,
                        std::uint64_t value) override;
  FlashResult DoRead(std::uint32_t page, std::uint32_t offset,
                     std::span<std::uint8_t> out) const override;
  std::uint32_t DoPageCount() const override { return pages_; }
  // True when this operation is the one the power cut interrupts.
  bool Interrupted();
  void Save() const;

  std::uint32_t pages_;
  std::vector<std::uint8_t> memory_;
  std::string path_;
  bool powered_ = true;
  long cut_after_ = -1;
  long operations_ = 0;
  std::mt19937_64 rng_;
};

}  // namespace mjc::hal
