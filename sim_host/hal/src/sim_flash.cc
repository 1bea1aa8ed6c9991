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
    : pages_(pages),
      memory_(static_cast<std::size_t>(pages) * kPageSize, 0xFF),
      ecc_bad_(memory_.size() / kDoubleWord) {
  if (path.empty()) return;
  const std::string ecc_path = path + ".ecc";
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
    ecc_file_.fd = ::open(ecc_path.c_str(), O_RDWR | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    SaveEcc();
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
  // The corrupt double words, when the file beside it has the right size (none else).
  ecc_file_.fd = ::open(ecc_path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (ecc_file_.fd >= 0) {
    std::vector<std::uint8_t> bits(ecc_bad_.size() / 8);
    if (::pread(ecc_file_.fd, bits.data(), bits.size(), 0) ==
        static_cast<ssize_t>(bits.size())) {
      for (std::size_t i = 0; i < ecc_bad_.size(); ++i)
        ecc_bad_[i] = ((bits[i / 8] >> (i % 8)) & 1u) != 0;
    }
    SaveEcc();
  }
}

void SimFlash::SaveEcc() {
  if (ecc_file_.fd < 0) return;
  std::vector<std::uint8_t> bits(ecc_bad_.size() / 8, 0);
  for (std::size_t i = 0; i < ecc_bad_.size(); ++i) {
    if (ecc_bad_[i])
      bits[i / 8] = static_cast<std::uint8_t>(bits[i / 8] | (1u << (i % 8)));
  }
  std::size_t done = 0;
  while (done < bits.size()) {
    const ssize_t n = ::pwrite(ecc_file_.fd, bits.data() + done, bits.size() - done,
                               static_cast<off_t>(done));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      ++file_errors_;
      return;
    }
    done += static_cast<std::size_t>(n);
  }
}

void SimFlash::SetEcc(std::size_t offset, std::size_t bytes, bool corrupt) {
  bool changed = false;
  for (std::size_t dw = offset / kDoubleWord; dw < (offset + bytes) / kDoubleWord; ++dw) {
    if (ecc_bad_[dw] != corrupt) {
      ecc_bad_[dw] = corrupt;
      changed = true;
    }
  }
  if (changed) SaveEcc();
}

bool SimFlash::AnyCorrupt(std::size_t offset, std::size_t bytes) const {
  if (bytes == 0) return false;
  for (std::size_t dw = offset / kDoubleWord; dw <= (offset + bytes - 1) / kDoubleWord;
       ++dw) {
    if (ecc_bad_[dw]) return true;
  }
  return false;
}

long SimFlash::corrupt_double_words() const {
  long n = 0;
  for (const bool b : ecc_bad_) n += b ? 1 : 0;
  return n;
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
    SetEcc(at, kPageSize, true);
    return FlashResult::kHardwareError;
  }
  std::memset(p, 0xFF, kPageSize);
  Save(at, kPageSize);
  SetEcc(at, kPageSize, false);
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
  if (AnyCorrupt(at, kDoubleWord)) {  // the erased-check's read takes the ECC error
    ++ecc_errors_;
    return FlashResult::kHardwareError;
  }
  std::uint64_t old = 0;
  std::memcpy(&old, p, sizeof old);
  if (old != ~std::uint64_t{0}) return FlashResult::kNotErased;
  if (Interrupted()) {
    const std::uint64_t mask = rng_();  // which bits made it
    const std::uint64_t garbage = (value & mask) | (old & ~mask);
    std::memcpy(p, &garbage, sizeof garbage);
    Save(at, kDoubleWord);
    SetEcc(at, kDoubleWord, true);
    return FlashResult::kHardwareError;
  }
  std::memcpy(p, &value, sizeof value);  // little-endian, as on the Cortex-M4
  Save(at, kDoubleWord);
  return FlashResult::kOk;
}

FlashResult SimFlash::DoRead(std::uint32_t page, std::uint32_t offset,
                             std::span<std::uint8_t> out) const {
  if (page >= pages_ || offset + out.size() > kPageSize) return FlashResult::kBadAddress;
  const std::size_t at = static_cast<std::size_t>(page) * kPageSize + offset;
  std::memcpy(out.data(), &memory_[at], out.size());
  if (AnyCorrupt(at, out.size())) {
    ++ecc_errors_;
    return FlashResult::kHardwareError;
  }
  return FlashResult::kOk;
}

}  // namespace mjc::hal
