#include "flash_powercut_rig.h"

#include <algorithm>
#include <functional>
#include <memory>
#include <optional>
#include <random>
#include <string>

#include "boot_rig.h"
#include "hal/sim/sim_flash.h"
#include "hal/stm32g4/flash.h"
#include "mjc/g474model/virtual_chip.h"

namespace mjc::boot::test {
namespace {

using protocol::BootState;
using protocol::StayReason;

// A flash that loses power: the simulated one, or the chip model behind its driver.
class World {
 public:
  virtual ~World() = default;
  virtual hal::Flash& flash() = 0;
  // Writes a file into the region directly (a debugger), before any cut.
  virtual void Install(std::span<const std::uint8_t> file) = 0;
  // The (count+1)-th erase or program from now is interrupted.
  virtual void CutPowerAfter(long count, std::uint64_t seed) = 0;
  // Power is back (a cut that has not happened yet is cancelled).
  virtual void PowerOn() = 0;
  // Every byte of the flash outside the application region.
  virtual std::vector<std::uint8_t> Outside() = 0;
  // Runs `body`; true when it ran to its end, false when a power cut stopped the chip.
  virtual bool Powered(const std::function<void()>& body) {
    body();
    return true;
  }
  // Every rule of the reference manual the driver broke, other than the cuts, and
  // anything else that went wrong in the world itself.
  virtual std::string Violations() { return ""; }
  // Reads so far that found an ECC double error.
  virtual long EccErrors() = 0;
};

std::vector<std::uint8_t> OutsideOf(const std::vector<std::uint8_t>& all) {
  std::vector<std::uint8_t> out;
  out.reserve(all.size());
  for (std::size_t i = 0; i < all.size(); ++i) {
    if (i < 8 * 2048 || i >= 128 * 2048) out.push_back(all[i]);
  }
  return out;
}

void FillOutside(std::vector<std::uint8_t>& all) {
  for (std::size_t i = 0; i < all.size(); ++i) {
    if (i >= 8 * 2048 && i < 128 * 2048) continue;
    all[i] = static_cast<std::uint8_t>(i * 31 + 7);
  }
}

// Something recognisable in the bootloader's, spare, identity and calibration pages
// of a simulated flash (made once, copied for each trial).
const hal::SimFlash& FilledSimFlash() {
  static const hal::SimFlash filled = [] {
    hal::SimFlash sim(256);
    std::vector<std::uint8_t> all(256 * 2048, 0xFF);
    FillOutside(all);
    for (std::uint32_t p = 0; p < 256; ++p) {
      if (p >= 8 && p < 128) continue;
      for (std::uint32_t off = 0; off < 2048; off += 8) {
        (void)sim.ProgramDoubleWord(p, off, protocol::GetLe(&all[p * 2048 + off], 8));
      }
    }
    return sim;
  }();
  return filled;
}

class SimWorld final : public World {
 public:
  hal::Flash& flash() override { return sim_; }
  void Install(std::span<const std::uint8_t> file) override { test::Install(sim_, file); }
  void CutPowerAfter(long count, std::uint64_t seed) override {
    sim_.CutPowerAfter(count, seed);
  }
  void PowerOn() override { sim_.PowerOn(); }
  long EccErrors() override { return sim_.ecc_errors(); }
  std::vector<std::uint8_t> Outside() override {
    std::vector<std::uint8_t> all(256 * 2048);
    for (std::uint32_t p = 0; p < 256; ++p) {
      (void)sim_.Read(p, 0, std::span<std::uint8_t>(all).subspan(p * 2048, 2048));
    }
    return OutsideOf(all);
  }

 private:
  hal::SimFlash sim_ = FilledSimFlash();
};

class ChipWorld final : public World {
 public:
  ChipWorld() {
    stm32g4::BindRegisterSpace(&chip_);
    // The NMI as the bootloader image's NmiHandler takes it
    // (firmware/boards/g474_bootloader/startup.cc).
    chip_.SetNmiHandler([] { (void)stm32g4::HandleFlashEccNmi(); });
    FillOutside(chip_.flash().mutable_contents());
    PowerOn();
  }
  ~ChipWorld() override { stm32g4::BindRegisterSpace(nullptr); }
  hal::Flash& flash() override { return *driver_; }
  void Install(std::span<const std::uint8_t> file) override {
    auto& memory = chip_.flash().mutable_contents();
    std::fill(memory.begin() + 8 * 2048, memory.begin() + 128 * 2048, 0xFF);
    std::copy(file.begin(), file.end(), memory.begin() + 8 * 2048);
  }
  void CutPowerAfter(long count, std::uint64_t seed) override {
    chip_.flash().CutPowerAfter(count, seed);
  }
  void PowerOn() override {
    chip_.flash().CutPowerAfter(-1, 0);
    // The bootloader runs with PRIMASK set (it polls its CAN controller), as its
    // start-up code leaves it after every reset.
    stm32g4::DisableInterrupts();
    // The bootloader's flash driver as the G474 image makes it: the application
    // region's pages writable, nothing else.
    driver_.emplace(kG474Layout.app_first_page, kG474Layout.app_pages);
    if (!driver_->Init()) problems_ += "the flash driver's Init failed at power-up\n";
  }
  std::vector<std::uint8_t> Outside() override {
    return OutsideOf(chip_.flash().contents());
  }
  long EccErrors() override { return chip_.flash().ecc_detections(); }
  bool Powered(const std::function<void()>& body) override {
    try {
      body();
      return true;
    } catch (const g474model::ChipReset& reset) {
      if (reset.cause != g474model::ResetCause::kPowerCut) {
        problems_ += "a reset other than the power cut\n";
      }
      return false;
    }
  }
  std::string Violations() override {
    std::string s = problems_;
    for (const auto& v : chip_.violations().entries()) {
      if (v.what.find("power cut") == std::string::npos)
        s += v.source + ": " + v.what + "\n";
    }
    return s;
  }

 private:
  g474model::VirtualChip chip_;
  std::optional<stm32g4::Stm32g4Flash> driver_;
  std::string problems_;
};

struct Boot {
  bool handed_over = false;
  StayReason reason = StayReason::kNone;
  bool powered = true;  // false: the power-up was cut (it performs no flash operation)
};

// Power-up after a cut: RAM random, the bootloader decides (the window passes).
Boot PowerUp(World& world, std::mt19937_64& rng) {
  BootHandoff handoff;
  std::uint32_t* words = &handoff.stay_magic;
  for (int i = 0; i < 8; ++i) words[i] = static_cast<std::uint32_t>(rng());
  Boot boot;
  boot.powered = world.Powered([&] {
    Board board(&world.flash(), &handoff);
    BootAction a = board.Start(/*software_reset=*/false);
    while (a == BootAction::kNone && board.boot.state() == BootState::kHoldWindow) {
      a = board.Step();
    }
    boot.handed_over = a == BootAction::kBoot;
    boot.reason = board.boot.reason();
  });
  return boot;
}

// The host updates the board to `file` (catching it in its hold window first). True
// when the update ran to the end; false when a refusal or a cut stopped it.
bool Update(World& world, std::span<const std::uint8_t> file) {
  bool done = false;
  BootHandoff handoff{};
  (void)world.Powered([&] {
    Board board(&world.flash(), &handoff);
    (void)board.Start();
    board.Send(protocol::Encode(protocol::BootHold{}, kNode));
    (void)board.Step();
    HostUpdate host;
    done = host.Run(board, file);
  });
  return done;
}

// Erase and program operations of one update of `file`; -1 when the uncut update did
// not complete.
long OperationsOf(std::span<const std::uint8_t> file) {
  hal::SimFlash sim(256);
  SpyFlash spy(&sim);
  BootHandoff handoff{};
  Board board(&spy, &handoff);
  (void)board.Start();
  HostUpdate host;
  if (!host.Run(board, file)) return -1;
  return static_cast<long>(spy.ops.size());
}

bool Whole(World& world, std::span<const std::uint8_t> file) {
  return RegionBytes(world.flash(), file.size()) ==
         std::vector<std::uint8_t>(file.begin(), file.end());
}

// The commit discipline, seen in the flash itself: a header that checks out (magic,
// its CRC, commit mark) stands only in front of the whole image it names. A header
// over a partial image would leave the image's CRC as the only thing between the board
// and a jump into it.
bool TornCommit(World& world, std::span<const std::uint8_t> old_file,
                std::span<const std::uint8_t> new_file) {
  const auto bytes = RegionBytes(world.flash(), kHeaderSize);
  ImageHeader h;
  if (DecodeHeader(std::span<const std::uint8_t, kHeaderSize>(bytes.data(), kHeaderSize),
                   &h) != ImageCheck::kValid) {
    return false;
  }
  for (const auto file : {old_file, new_file}) {
    if (file.size() == kHeaderArea + h.length &&
        std::equal(bytes.begin(), bytes.end(), file.begin())) {
      return !Whole(world, file);
    }
  }
  return true;  // a header the host never sent
}

// One trial: the board holds `old_file` (or nothing), the host updates it to
// `new_file`, and power fails at each of `cuts` in turn (each counted from the start
// of an update attempt). Returns the reason when the rule broke, "" when it held.
// `*ecc_read`: whether the board's own reads (its power-ups and updates, not this
// rig's checks) found an ECC double error the cuts left.
std::string Trial(World& world, std::span<const std::uint8_t> old_file,
                  std::span<const std::uint8_t> new_file, const std::vector<long>& cuts,
                  std::uint64_t seed, bool* ecc_read) {
  std::mt19937_64 rng(seed);
  long board_ecc = 0;  // ECC errors the board's reads found
  const auto board = [&](const auto& run) {
    const long before = world.EccErrors();
    auto r = run();
    board_ecc += world.EccErrors() - before;
    return r;
  };
  struct Done {
    ~Done() { *flag = *count > 0; }
    bool* flag;
    long* count;
  } done{ecc_read, &board_ecc};
  if (!old_file.empty()) world.Install(old_file);
  const auto outside = world.Outside();
  bool updated = false;
  for (const long cut : cuts) {
    world.CutPowerAfter(cut, rng());
    updated = board([&] { return Update(world, new_file); });
    world.PowerOn();
    if (TornCommit(world, old_file, new_file)) {
      return "a header that checks out in front of an image that is not whole";
    }
    const Boot boot = board([&] { return PowerUp(world, rng); });
    if (!boot.powered) return "the power-up after the cut lost power";
    if (boot.handed_over) {
      const bool is_new = Whole(world, new_file);
      if (!is_new && !(old_file.size() > 0 && Whole(world, old_file))) {
        return "handed over to an image that is neither the old nor the new one whole";
      }
      if (is_new) {
        updated = true;
        break;
      }
    } else if (boot.reason != StayReason::kNoValidImage) {
      return "stayed for an unexpected reason";
    } else if (updated) {
      return "the update completed, yet the new image does not boot";
    }
  }
  if (!updated) {
    // Staying: the bootloader must take the image again, and then start it.
    if (!board([&] { return Update(world, new_file); }))
      return "the bootloader did not take the image again";
    const Boot boot = board([&] { return PowerUp(world, rng); });
    if (!boot.powered || !boot.handed_over || !Whole(world, new_file)) {
      return "after the complete update the new image does not boot";
    }
  }
  if (world.Outside() != outside) return "flash outside the application region changed";
  return "";
}

// Every operation of an update (one cut), for a board with and without an old image,
// then `random` trials at random points (1-3 cuts, random image sizes).
template <class MakeWorld>
PowerCutSweep PowerCuts(MakeWorld make_world, int random, std::size_t step_bytes,
                        std::size_t max_random_bytes) {
  PowerCutSweep sweep;
  const auto note = [&](const std::string& why, const std::string& where, bool ecc_read) {
    ++sweep.points;
    if (ecc_read) ++sweep.ecc_reads;
    if (why.empty()) return;
    ++sweep.bricked;
    if (sweep.first_failure.empty()) sweep.first_failure = where + ": " + why;
  };
  const auto old_file = MakeFile(MakeImage(step_bytes + 1000, 101));
  const auto new_file = MakeFile(MakeImage(step_bytes, 102));
  const long steps = OperationsOf(new_file);
  if (steps < 0) {
    note("the update without a cut did not complete", "counting its operations", false);
    return sweep;
  }
  for (long cut = 0; cut <= steps; ++cut) {  // `steps`: the cut comes after the end
    for (int with_old = 0; with_old < 2; ++with_old) {
      auto world = make_world();
      bool ecc_read = false;
      std::string why =
          Trial(*world,
                with_old ? std::span<const std::uint8_t>(old_file)
                         : std::span<const std::uint8_t>(),
                new_file, {cut}, 1000u * static_cast<std::uint64_t>(cut) + 7u, &ecc_read);
      if (why.empty()) why = world->Violations();
      note(why, "step " + std::to_string(cut) + (with_old ? " over an old image" : ""),
           ecc_read);
    }
  }
  std::mt19937_64 rng(0xF1A5'0000u + static_cast<std::uint64_t>(step_bytes));
  for (int trial = 0; trial < random; ++trial) {
    const std::size_t bytes = 64 + rng() % max_random_bytes;
    const auto a = MakeFile(
        MakeImage(64 + rng() % max_random_bytes, static_cast<std::uint32_t>(rng())));
    const auto b = MakeFile(MakeImage(bytes, static_cast<std::uint32_t>(rng())));
    const long ops = OperationsOf(b);
    if (ops < 0) {
      note("the update without a cut did not complete",
           "random trial " + std::to_string(trial), false);
      continue;
    }
    std::vector<long> cuts(1 + rng() % 3);
    for (long& c : cuts)
      c = static_cast<long>(rng() % static_cast<std::uint64_t>(ops + 2));
    auto world = make_world();
    bool ecc_read = false;
    std::string why = Trial(*world, rng() % 4 == 0 ? std::span<const std::uint8_t>() : a,
                            b, cuts, rng(), &ecc_read);
    if (why.empty()) why = world->Violations();
    note(why, "random trial " + std::to_string(trial), ecc_read);
  }
  return sweep;
}

}  // namespace

PowerCutSweep SimulatedFlashPowerCuts() {
  return PowerCuts([] { return std::make_unique<SimWorld>(); }, 1500,
                   /*step_bytes=*/5000, /*max_random_bytes=*/12000);
}

PowerCutSweep G474FlashModelPowerCuts() {
  return PowerCuts([] { return std::make_unique<ChipWorld>(); }, 1000,
                   /*step_bytes=*/1400, /*max_random_bytes=*/3000);
}

}  // namespace mjc::boot::test
