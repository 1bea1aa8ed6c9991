#include "hal/sim/sim_flash.h"

#include <cstring>
#include <fstream>
#include <iterator>

namespace mjc::hal {

SimFlash::SimFlash(std::uint32_t pages, std::string path, std::string* why)
    : pages_(pages),
      memory_(static_cast<std::size_t>(pages) * kPageSize, 0xFF),
      path_(std::move(path)) {
  if (path_.empty()) return;
  std::ifstream in(path_, std::ios::binary);
  if (!in) return;  // a new file: erased flash
  std::vector<std::uint8_t> data((std::istreambuf_iterator<char>(in)),
                                 std::istreambuf_iterator<char>());
  if (data.size() == memory_.size()) {
    memory_ = std::move(data);
  } else if (why != nullptr) {
    *why = path_ + " holds " + std::to_string(data.size()) + " bytes, not " +
           std::to_string(memory_.size()) + ": starting from erased flash";
  }
}

void SimFlash::Save() const {
  if (path_.empty()) return;
  std::ofstream out(path_, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(memory_.data()),
            static_cast<std::streamsize>(memory_.size()));
}

void SimFlash::CutPowerAfter(long count, std::uint64_t seed) {
  cut_after_ = count;
  rng_.seed(seed);
}

bool SimFlash::Interrupted() {
  ++operations_;
  if (cut_after_ < 0) return false;
  if (cut_after_-- > 0) return false;
  powered_ = false;
  return true;
}

FlashResult SimFlash::DoErasePage(std::uint32_t page) {
  if (!powered_) return FlashResult::kHardwareError;
  if (page >= pages_) return FlashResult::kBadAddress;
  std::uint8_t* p = &memory_[static_cast<std::size_t>(page) * kPageSize];
  if (Interrupted()) {
    for (std::size_t i = 0; i < kPageSize; ++i) p[i] = static_cast<std::uint8_t>(rng_());
    Save();
    return FlashResult::kHardwareError;
  }
  std::memset(p, 0xFF, kPageSize);
  Save();
  return FlashResult::kOk;
}

FlashResult SimFlash::DoProgram(std::uint32_t page, std::uint32_t offset,
                                std::uint64_t value) {
  if (!powered_) return FlashResult::kHardwareError;
  if (page >= pages_ || offset % kDoubleWord != 0 || offset + kDoubleWord > kPageSize) {
    return FlashResult::kBadAddress;
  }
  std::uint8_t* p = &memory_[static_cast<std::size_t>(page) * kPageSize + offset];
  std::uint64_t old = 0;
  std::memcpy(&old, p, sizeof old);
  if (old != ~std::uint64_t{0}) return FlashResult::kNotErased;
  if (Interrupted()) {
    const std::uint64_t mask = rng_();  // which bits made it
    const std::uint64_t garbage = (value & mask) | (old & ~mask);
    std::memcpy(p, &garbage, sizeof garbage);
    Save();
    return FlashResult::kHardwareError;
  }
  std::memcpy(p, &value, sizeof value);  // little-endian, as on the Cortex-M4
  Save();
  return FlashResult::kOk;
}

FlashResult SimFlash::DoRead(std::uint32_t page, std::uint32_t offset,
                             std::span<std::uint8_t> out) const {
  if (page >= pages_ || offset + out.size() > kPageSize) return FlashResult::kBadAddress;
  std::memcpy(out.data(), &memory_[static_cast<std::size_t>(page) * kPageSize + offset],
              out.size());
  return FlashResult::kOk;
}

}  // namespace mjc::hal
