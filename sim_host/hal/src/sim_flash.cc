#include "hal/sim/sim_flash.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <utility>

namespace mjc::hal {

SimFlash::SimFlash(std::uint32_t pages, std::string path, std::string* why)
    : pages_(pages), memory_(static_cast<std::size_t>(pages) * kPageSize, 0xFF) {
  if (path.empty()) return;
  const int fd = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (fd < 0) {
    if (why != nullptr) *why = path + ": " + std::strerror(errno) + ": not kept";
    return;
  }
  struct stat st {};
  if (::fstat(fd, &st) != 0) {
    if (why != nullptr) *why = path + ": " + std::strerror(errno) + ": not kept";
    ::close(fd);
    return;
  }
  const auto size = static_cast<std::size_t>(st.st_size);
  if (size == 0) {  // a new file: the whole chip, erased
    file_.fd = fd;
    Save(0, memory_.size());
    return;
  }
  if (size != memory_.size()) {
    if (why != nullptr) {
      *why = path + " holds " + std::to_string(size) + " bytes, not " +
             std::to_string(memory_.size()) + ": left untouched";
    }
    ::close(fd);
    return;
  }
  std::size_t done = 0;
  while (done < size) {
    const ssize_t n =
        ::pread(fd, memory_.data() + done, size - done, static_cast<off_t>(done));
    if (n <= 0) {
      if (n < 0 && errno == EINTR) continue;
      if (why != nullptr) *why = path + ": cannot be read: left untouched";
      std::fill(memory_.begin(), memory_.end(), std::uint8_t{0xFF});
      ::close(fd);
      return;
    }
    done += static_cast<std::size_t>(n);
  }
  file_.fd = fd;
}

SimFlash::MirrorFile::~MirrorFile() {
  if (fd >= 0) ::close(fd);
}

SimFlash::MirrorFile& SimFlash::MirrorFile::operator=(const MirrorFile& other) {
  if (this != &other && fd >= 0) {
    ::close(fd);
    fd = -1;
  }
  return *this;
}

SimFlash::MirrorFile::MirrorFile(MirrorFile&& other) noexcept
    : fd(std::exchange(other.fd, -1)) {}

SimFlash::MirrorFile& SimFlash::MirrorFile::operator=(MirrorFile&& other) noexcept {
  if (this != &other) {
    if (fd >= 0) ::close(fd);
    fd = std::exchange(other.fd, -1);
  }
  return *this;
}

void SimFlash::Save(std::size_t offset, std::size_t bytes) {
  if (file_.fd < 0) return;
  while (bytes > 0) {
    const ssize_t n =
        ::pwrite(file_.fd, memory_.data() + offset, bytes, static_cast<off_t>(offset));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      ++file_errors_;
      return;
    }
    offset += static_cast<std::size_t>(n);
    bytes -= static_cast<std::size_t>(n);
  }
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
  const std::size_t at = static_cast<std::size_t>(page) * kPageSize;
  std::uint8_t* p = &memory_[at];
  if (Interrupted()) {
    for (std::size_t i = 0; i < kPageSize; ++i) p[i] = static_cast<std::uint8_t>(rng_());
    Save(at, kPageSize);
    return FlashResult::kHardwareError;
  }
  std::memset(p, 0xFF, kPageSize);
  Save(at, kPageSize);
  return FlashResult::kOk;
}

FlashResult SimFlash::DoProgram(std::uint32_t page, std::uint32_t offset,
                                std::uint64_t value) {
  if (!powered_) return FlashResult::kHardwareError;
  if (page >= pages_ || offset % kDoubleWord != 0 || offset + kDoubleWord > kPageSize) {
    return FlashResult::kBadAddress;
  }
  const std::size_t at = static_cast<std::size_t>(page) * kPageSize + offset;
  std::uint8_t* p = &memory_[at];
  std::uint64_t old = 0;
  std::memcpy(&old, p, sizeof old);
  if (old != ~std::uint64_t{0}) return FlashResult::kNotErased;
  if (Interrupted()) {
    const std::uint64_t mask = rng_();  // which bits made it
    const std::uint64_t garbage = (value & mask) | (old & ~mask);
    std::memcpy(p, &garbage, sizeof garbage);
    Save(at, kDoubleWord);
    return FlashResult::kHardwareError;
  }
  std::memcpy(p, &value, sizeof value);  // little-endian, as on the Cortex-M4
  Save(at, kDoubleWord);
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
