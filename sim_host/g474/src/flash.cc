#include "mjc/g474model/flash.h"

#include <fcntl.h>
#include <unistd.h>

#include <cstring>
#include <fstream>
#include <iterator>

namespace mjc::g474model {
namespace {
constexpr std::uint32_t kPg = 1u << 0, kPer = 1u << 1, kMer1 = 1u << 2, kBker = 1u << 11,
                        kMer2 = 1u << 15, kStart = 1u << 16, kOptstrt = 1u << 17,
                        kFstpg = 1u << 18, kOblLaunch = 1u << 27, kOptlock = 1u << 30,
                        kLock = 1u << 31;
constexpr std::uint32_t kSrW1c = 0x0000C3FBu;  // every flag but BSY
// Flags that block the next operation until software clears them (RM0440 §5.3.8).
constexpr std::uint32_t kBlocking = Flash::kProgerr | Flash::kWrperr | Flash::kPgaerr |
                                    Flash::kSizerr | Flash::kPgserr | Flash::kMisserr |
                                    Flash::kFasterr;

// One write to a key register (KEYR, OPTKEYR: RM0440 §5.3.5): the first key, then the
// second, unlock; anything else ends the sequence (`*stage`: 1 after the first key).
enum class KeyStep : std::uint8_t { kFirstKey, kUnlocked, kWrong };
KeyStep NextKey(int* stage, std::uint32_t value, std::uint32_t first,
                std::uint32_t second) {
  if (*stage == 0 && value == first) {
    *stage = 1;
    return KeyStep::kFirstKey;
  }
  const bool unlocked = *stage == 1 && value == second;
  *stage = 0;
  return unlocked ? KeyStep::kUnlocked : KeyStep::kWrong;
}
}  // namespace

Flash::Flash(ViolationLog* log, FlashConfig config)
    : log_(log),
      config_(std::move(config)),
      memory_(kSize, 0xFF),
      ecc_bad_(kSize / 8),
      options_(log, config_.option_program_time) {
  if (!config_.path.empty()) {
    bool keep = true, fresh = true;
    std::ifstream in(config_.path, std::ios::binary);
    if (in) {
      std::vector<std::uint8_t> data((std::istreambuf_iterator<char>(in)),
                                     std::istreambuf_iterator<char>());
      fresh = false;
      // The array, then the option bytes' block (a file without one: factory options).
      keep = data.size() == memory_.size() ||
             data.size() == memory_.size() + OptionBytes::kFileBytes;
      if (keep && data.size() > memory_.size()) {
        options_.Restore(&data[kSize], OptionBytes::kFileBytes);
        data.resize(kSize);
      }
      if (keep) memory_ = std::move(data);
    }
    if (keep) file_ = ::open(config_.path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fresh) Save(0, kSize);
    options_.Persist(file_, kSize);
    if (file_ >= 0) {
      // The corrupt double words beside the array: a bit each (a missing file or one
      // of another size: none corrupt).
      const std::string ecc_path = config_.path + ".ecc";
      std::ifstream ecc_in(ecc_path, std::ios::binary);
      if (ecc_in && !fresh) {
        std::vector<std::uint8_t> bits((std::istreambuf_iterator<char>(ecc_in)),
                                       std::istreambuf_iterator<char>());
        if (bits.size() == ecc_bad_.size() / 8) {
          for (std::size_t i = 0; i < ecc_bad_.size(); ++i)
            ecc_bad_[i] = ((bits[i / 8] >> (i % 8)) & 1u) != 0;
        }
      }
      ecc_file_ = ::open(ecc_path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
      SaveEcc();
    }
  }
  Reset();
}

Flash::~Flash() {
  if (file_ >= 0) ::close(file_);
  if (ecc_file_ >= 0) ::close(ecc_file_);
}

void Flash::SaveEcc() const {
  if (ecc_file_ < 0) return;
  std::vector<std::uint8_t> bits(ecc_bad_.size() / 8, 0);
  for (std::size_t i = 0; i < ecc_bad_.size(); ++i) {
    if (ecc_bad_[i])
      bits[i / 8] = static_cast<std::uint8_t>(bits[i / 8] | (1u << (i % 8)));
  }
  const std::uint8_t* p = bits.data();
  std::size_t left = bits.size();
  off_t at = 0;
  while (left > 0) {
    const ssize_t n = ::pwrite(ecc_file_, p, left, at);
    if (n <= 0) return;  // a full disk: the state in memory stays right
    p += n, at += n, left -= static_cast<std::size_t>(n);
  }
}

void Flash::SetEcc(std::uint32_t offset, std::uint32_t bytes, bool corrupt) {
  bool changed = false;
  for (std::uint32_t dw = offset / 8; dw < (offset + bytes) / 8; ++dw) {
    if (ecc_bad_[dw] != corrupt) {
      ecc_bad_[dw] = corrupt;
      changed = true;
    }
  }
  if (changed) SaveEcc();
}

long Flash::corrupt_double_words() const {
  long n = 0;
  for (const bool b : ecc_bad_) n += b ? 1 : 0;
  return n;
}

void Flash::Save(std::uint32_t offset, std::uint32_t bytes) const {
  if (file_ < 0) return;
  const std::uint8_t* p = &memory_[offset];
  auto at = static_cast<off_t>(offset);
  while (bytes > 0) {
    const ssize_t n = ::pwrite(file_, p, bytes, at);
    if (n <= 0) return;  // a full disk: the array in memory stays right
    p += n, at += n, bytes -= static_cast<std::uint32_t>(n);
  }
}

void Flash::Reset() {
  if (op_.kind != OpKind::kNone) Complete();
  // ACR reset value from the SVD (0x00040601: LATENCY = 1, ICEN, DCEN, DBG_SWEN).
  acr_ = 0x00040601u;
  sr_ = 0;
  eccr_ = 0;
  nmi_ = false;
  cr_ = kLock | kOptlock;
  options_.Reset();  // FLASH_OPTR: the option bytes loaded last
  if (options_.load_error()) sr_ |= kOptverr;
  // WRP areas as the factory option bytes leave them: start > end, no protection.
  for (auto& w : wrp_) w = 0x0000007Fu;
  key_stage_ = optkey_stage_ = 0;
  keys_dead_ = false;
  have_first_ = false;
  stall_until_ = 0;
}

void Flash::CutPowerAfter(long count, std::uint64_t seed) {
  cut_after_ = count;
  rng_.seed(seed);
}

void Flash::Error(std::uint32_t flags, const std::string& why) {
  sr_ |= flags;
  if (cr_ & (1u << 25)) sr_ |= kOperr;  // OPERR only with ERRIE
  log_->Report(now_, "FLASH", why);
}

bool Flash::ErrorsPending() const { return (sr_ & kBlocking) != 0; }

bool Flash::WriteProtected(std::uint32_t offset) const {
  const int bank = BankOf(offset);
  const std::uint32_t page = (offset % (kSize / 2)) / kPageSize;
  for (int i = 0; i < 2; ++i) {
    const std::uint32_t w = wrp_[bank * 2 + i];
    const std::uint32_t start = w & 0x7Fu, end = (w >> 16) & 0x7Fu;
    if (start <= end && page >= start && page <= end) return true;
  }
  return false;
}

void Flash::StartOperation(Operation op, Picoseconds duration) {
  ++operations_;
  op.end = now_ + duration;
  op.cut_at = kNever;
  if (cut_after_ >= 0 && cut_after_-- == 0) {
    op.cut_at =
        now_ + static_cast<Picoseconds>(rng_() % static_cast<std::uint64_t>(duration));
  }
  op_ = op;
}

void Flash::Complete() {
  std::uint8_t* p = &memory_[op_.offset];
  if (op_.kind == OpKind::kErase) {
    std::memset(p, 0xFF, op_.length);
  } else if (op_.kind == OpKind::kProgram) {
    std::memcpy(p, &op_.value, 8);  // little-endian, as the Cortex-M4 stores it
  }
  Save(op_.offset, op_.length);
  // A whole erase writes every cell and ECC bit anew; a program over a corrupt double
  // word is only accepted with all zeros (WriteMemory), which clears every data and
  // ECC bit: either way the double words match their ECC again.
  SetEcc(op_.offset, op_.length, false);
  op_ = Operation{};
  if (cr_ & (1u << 24)) sr_ |= kEop;  // EOP only when EOPIE is set
}

void Flash::Interrupt() {
  std::uint8_t* p = &memory_[op_.offset];
  if (op_.kind == OpKind::kErase) {
    for (std::uint32_t i = 0; i < op_.length; ++i)
      p[i] = static_cast<std::uint8_t>(rng_());
  } else if (op_.kind == OpKind::kProgram) {
    std::uint64_t old = 0;
    std::memcpy(&old, p, 8);
    const std::uint64_t mask = rng_();  // which bits made it
    const std::uint64_t mixed = (op_.value & mask) | (old & ~mask);
    std::memcpy(p, &mixed, 8);
  }
  Save(op_.offset, op_.length);
  // The ECC bits were cut with the data: they no longer match it.
  SetEcc(op_.offset, op_.length, true);
  op_ = Operation{};
}

bool Flash::PowerLost() {
  const bool options = options_.PowerLost();
  if (op_.kind == OpKind::kNone) return options;
  Interrupt();
  return true;
}

void Flash::Advance(Picoseconds now) {
  now_ = now;
  options_.Advance(now);
  if (op_.kind == OpKind::kNone) return;
  if (now >= op_.cut_at) {
    Interrupt();
    log_->Report(now, "FLASH", "power cut during a flash operation (scheduled)");
    if (power_cut_hook_) power_cut_hook_();
    return;
  }
  if (now >= op_.end) Complete();
}

Picoseconds Flash::NextEvent() const {
  if (op_.kind == OpKind::kNone) return options_.NextEvent();
  return op_.cut_at < op_.end ? op_.cut_at : op_.end;
}

RegisterTable<Flash> Flash::Registers() {
  using R = Register<Flash>;
  // ACR, the key registers, CR and the option registers write through code of their own
  // (see Write); SR and the WRP areas read through it.
  static constexpr R kTable[] = {
      R::ReadWrite(0x00, &Flash::acr_, 0x00047F0Fu),
      R::Fixed(0x04),  // PDKEYR: write-only, power-down not modelled
      R::Fixed(0x08),  // KEYR: write-only
      R::Fixed(0x0C),  // OPTKEYR: write-only
      R::ClearByWriting1(0x10, &Flash::sr_, kSrW1c),
      R::ReadWrite(0x14, &Flash::cr_),
      R::ReadOnly(0x18, &Flash::eccr_),  // written through Write
      // 0x20 FLASH_OPTR: OptionBytes (see Read and Write).
      R::Fixed(0x24, 0xFFFF0000u),
      R::Fixed(0x28),
      R::Fixed(0x44, 0xFFFF0000u),
      R::Fixed(0x48),
      R::Fixed(0x70, 0xFFF0FF00u),
      R::Fixed(0x74, 0xFFFFFF00u),
  };
  return kTable;
}

const std::uint32_t* Flash::Wrp(std::uint32_t offset) const {
  switch (offset) {
    case 0x2C:
      return &wrp_[0];
    case 0x30:
      return &wrp_[1];
    case 0x4C:
      return &wrp_[2];
    case 0x50:
      return &wrp_[3];
    default:
      return nullptr;
  }
}

bool Flash::Read(const Access& a, std::uint32_t* v) {
  if (a.offset == 0x10) {
    *v = sr_ | (busy() || options_.busy() ? kBsy : 0);
    return true;
  }
  if (a.offset == OptionBytes::kOffset) {
    *v = options_.reg();
    return true;
  }
  if (a.offset == 0x14 && options_.busy()) {
    *v = cr_ | kOptstrt;  // OPTSTRT reads 1 until BSY clears
    return true;
  }
  if (const std::uint32_t* wrp = Wrp(a.offset)) {
    *v = *wrp;
    return true;
  }
  return ReadTableRegister(Registers(), *this, a.offset, v);
}

bool Flash::Write(const Access& a) {
  const std::uint32_t v = a.value & a.mask;
  switch (a.offset) {
    case 0x00: {
      const std::uint32_t next = a.Merged(acr_) & 0x00047F0Fu;
      // ICRST/DCRST "can be written only when the cache is disabled".
      if ((next & (1u << 11)) && (acr_ & (1u << 9))) {
        log_->Report(now_, "FLASH", "ACR.ICRST set while ICEN = 1 (cache must be off)");
      }
      if ((next & (1u << 12)) && (acr_ & (1u << 10))) {
        log_->Report(now_, "FLASH", "ACR.DCRST set while DCEN = 1 (cache must be off)");
      }
      acr_ = next;
      return true;
    }
    case 0x08: {
      if (keys_dead_ || !locked()) {
        log_->Report(now_, "FLASH",
                     keys_dead_ ? "KEYR written after a wrong key: locked until reset"
                                : "KEYR written while CR is already unlocked");
        return true;
      }
      const KeyStep step = NextKey(&key_stage_, v, kKey1, kKey2);
      if (step == KeyStep::kUnlocked) {
        cr_ &= ~kLock;
      } else if (step == KeyStep::kWrong) {
        keys_dead_ = true;
        log_->Report(now_, "bus",
                     "bus error (HardFault): wrong FLASH_KEYR sequence (" + Hex(v) +
                         "); FLASH_CR locked until the next reset (RM0440 §5.3.5)");
      }
      return true;
    }
    case 0x0C: {
      if (locked()) {
        log_->Report(now_, "FLASH", "OPTKEYR written while CR.LOCK = 1: ignored");
        return true;
      }
      const KeyStep step = NextKey(&optkey_stage_, v, kOptKey1, kOptKey2);
      if (step == KeyStep::kUnlocked) {
        cr_ &= ~kOptlock;
      } else if (step == KeyStep::kWrong) {
        keys_dead_ = true;
        cr_ |= kLock | kOptlock;
        log_->Report(now_, "bus",
                     "bus error (HardFault): wrong FLASH_OPTKEYR sequence; locked until "
                     "the next reset");
      }
      return true;
    }
    case 0x14: {
      if (locked()) {
        // LOCK can only be set; everything else is frozen while locked.
        if (v != (cr_ & a.mask)) {
          log_->Report(now_, "FLASH", "FLASH_CR written while locked: ignored");
        }
        return true;
      }
      std::uint32_t next = a.Merged(cr_) & 0xFF0F8BFFu;
      if (next & kLock) next |= kOptlock;
      if (!(cr_ & kOptlock)) {
        // OPTLOCK: software may set it; clearing needs the option keys.
      } else {
        next |= kOptlock;
      }
      const bool start = (next & kStart) != 0;
      cr_ = next & ~kStart;
      if (!(cr_ & kPg)) have_first_ = false;
      if (next & kOptstrt) {
        cr_ &= ~kOptstrt;
        options_.Start((cr_ & kOptlock) != 0, busy(), now_);
      }
      if (next & kOblLaunch) {
        cr_ &= ~kOblLaunch;
        options_.Launch((cr_ & kOptlock) != 0, now_);
      }
      if (next & kFstpg) {
        log_->Report(now_, "FLASH", "FSTPG: fast programming is not modelled");
      }
      if (!start) return true;
      if (busy() || options_.busy()) {
        log_->Report(now_, "FLASH", "CR.STRT while BSY = 1: ignored");
        return true;
      }
      if (ErrorsPending()) {
        Error(kPgserr,
              "erase started while an earlier error flag is still set in FLASH_SR "
              "(PGSERR, RM0440 §5.3.8)");
        return true;
      }
      if (cr_ & kPg) {
        Error(kPgserr, "erase started with CR.PG set (PGSERR)");
        return true;
      }
      if (cr_ & kPer) {
        const std::uint32_t page = (cr_ >> 3) & 0x7Fu;
        const std::uint32_t bank = (cr_ & kBker) ? 1 : 0;
        const std::uint32_t offset = bank * (kSize / 2) + page * kPageSize;
        if (WriteProtected(offset)) {
          Error(kWrperr, "page erase in a write-protected area (WRPERR)");
          return true;
        }
        Operation op;
        op.kind = OpKind::kErase;
        op.offset = offset;
        op.length = kPageSize;
        StartOperation(op, config_.page_erase_time);
        return true;
      }
      if (cr_ & (kMer1 | kMer2)) {
        if ((cr_ & kMer1) && (cr_ & kMer2)) {
          log_->Report(now_, "FLASH",
                       "MER1 and MER2 together: erasing bank 1 then 2 "
                       "is modelled as one bank (bank 1)");
        }
        Operation op;
        op.kind = OpKind::kErase;
        op.offset = (cr_ & kMer1) ? 0 : kSize / 2;
        op.length = kSize / 2;
        StartOperation(op, config_.mass_erase_time);
        return true;
      }
      log_->Report(now_, "FLASH", "CR.STRT with neither PER nor MER1/MER2: nothing done");
      return true;
    }
    case 0x18:
      // ECCCIE read-write; ECCC and ECCD cleared by writing 1; the rest read-only.
      eccr_ = (eccr_ & ~kEcccie) | (v & kEcccie);
      eccr_ &= ~(v & (kEccc | kEccd));
      return true;
    case OptionBytes::kOffset:
      options_.Write(a, (cr_ & kOptlock) != 0, now_);
      return true;
    case 0x24:
    case 0x28:
    case 0x2C:
    case 0x30:
    case 0x44:
    case 0x48:
    case 0x4C:
    case 0x50:
    case 0x70:
    case 0x74:
      log_->Report(now_, "FLASH", "option-byte register written: not modelled");
      return true;
    default:
      return WriteTableRegister(Registers(), *this, a);
  }
}

bool Flash::ReadMemory(std::uint32_t address, unsigned bytes, std::uint32_t* value) {
  if (InInfo(address)) {
    if (address >= 0x1FFF75E0u) {
      *value = 512;  // FLASH_SIZE in KB
      return true;
    }
    const std::uint32_t word = config_.uid[(address - 0x1FFF7590u) / 4];
    *value = bytes == 2 ? (word >> (8 * (address & 2u))) & 0xFFFFu : word;
    return true;
  }
  if (!InArray(address)) return false;
  const std::uint32_t offset = address - kArrayBase;
  if (busy() && BankOf(op_.offset) == BankOf(offset)) {
    // Reading the bank being written stalls the bus until the operation ends.
    stall_until_ = op_.end < op_.cut_at ? op_.end : op_.cut_at;
    return false;  // the chip advances time and retries
  }
  if (ecc_bad_[offset / 8]) {
    // A double error: the data go out as read, ECCD and the NMI report it. ADDR_ECC and
    // BK_ECC keep the first error's place until the flags are cleared.
    ++ecc_detections_;
    if ((eccr_ & (kEccc | kEccd)) == 0) {
      const std::uint32_t in_bank = (offset % (kSize / 2)) & ~7u;
      eccr_ = (eccr_ & kEcccie) | (BankOf(offset) == 1 ? kBkEcc : 0u) | in_bank;
    }
    eccr_ |= kEccd;
    nmi_ = true;
  }
  std::uint32_t v = 0;
  std::memcpy(&v, &memory_[offset], bytes);
  *value = v;
  return true;
}

bool Flash::WriteMemory(std::uint32_t address, std::uint32_t value, unsigned bytes) {
  const std::uint32_t offset = address - kArrayBase;
  if (busy()) {
    stall_until_ = op_.end < op_.cut_at ? op_.end : op_.cut_at;
    return false;
  }
  if (!(cr_ & kPg) || locked()) {
    Error(kPgserr, "write to flash " + Hex(address) +
                       " without CR.PG set (PGSERR, RM0440 §5.3.8)");
    return true;
  }
  if (bytes != 4) {
    Error(kSizerr | kPgserr, "half-word write to flash " + Hex(address) +
                                 ": only 32-bit writes program (SIZERR)");
    have_first_ = false;
    return true;
  }
  if (!have_first_) {
    if (ErrorsPending()) {
      Error(kPgserr,
            "programming started while an earlier error flag is still set "
            "(PGSERR)");
      return true;
    }
    if (offset % 8 != 0) {
      Error(kPgaerr, "first word of a double word at " + Hex(address) +
                         ", not 8-byte aligned (PGAERR)");
      return true;
    }
    have_first_ = true;
    first_offset_ = offset;
    first_word_ = value;
    return true;
  }
  have_first_ = false;
  if (offset != first_offset_ + 4) {
    Error(kPgaerr, "second word at " + Hex(address) + " is not the first word's +4 (" +
                       Hex(kArrayBase + first_offset_ + 4) + "): PGAERR");
    return true;
  }
  if (WriteProtected(first_offset_)) {
    Error(kWrperr, "program in a write-protected area (WRPERR)");
    return true;
  }
  const std::uint64_t data =
      static_cast<std::uint64_t>(first_word_) | (static_cast<std::uint64_t>(value) << 32);
  std::uint64_t old = 0;
  std::memcpy(&old, &memory_[first_offset_], 8);
  // "PROGERR: ... the double word to be programmed contains a value different from
  // 0xFFFF FFFF FFFF FFFF before programming, except if the data to write is 0x0000
  // 0000 0000 0000" (RM0440 FLASH_SR).
  if (old != ~std::uint64_t{0} && data != 0) {
    Error(kProgerr, "double word at " + Hex(kArrayBase + first_offset_) +
                        " is not erased (PROGERR)");
    return true;
  }
  Operation op;
  op.kind = OpKind::kProgram;
  op.offset = first_offset_;
  op.length = 8;
  op.value = data;
  StartOperation(op, config_.program_time);
  return true;
}

}  // namespace mjc::g474model
