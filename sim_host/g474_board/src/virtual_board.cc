#include "mjc/g474board/virtual_board.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdarg>
#include <exception>
#include <filesystem>
#include <numeric>
#include <stdexcept>

#include "board.h"
#include "hal/stm32g4/flash.h"
#include "hal/stm32g4/mmio.h"
#include "interrupts.h"

namespace mjc::g474board {
namespace {

using g474model::kPsPerSecond;
using g474model::Picoseconds;
using g474model::Pin;
using g474model::PinId;

// The board around the chip, as its schematic wires it. Stated here, for the world,
// independently of the firmware's pin table (firmware/boards/g474_joint/pins.h): a pin
// or alternate function wrong there leaves the world unconnected (the encoder does not
// count, the bridge floats, the sensor sees no clock) and the runs and tests fail.
constexpr double kCrystalHz = 24e6;            // the HSE crystal on PF0/PF1
constexpr PinId kBridgeIn1 = Pin('A', 8);      // gate driver leg A (high-side input)
constexpr PinId kBridgeIn2 = Pin('A', 9);      // gate driver leg B (high-side input)
constexpr PinId kBridgeEnable = Pin('B', 10);  // gate driver enable
constexpr PinId kEncoderA = Pin('C', 6);
constexpr PinId kEncoderB = Pin('C', 7);
constexpr g474model::SpiWiring kJointEncoder{
    .sck = Pin('A', 5), .miso = Pin('A', 6), .mosi = Pin('A', 7), .cs = Pin('A', 4)};
constexpr PinId kCanTxd = Pin('A', 12);  // the transceiver's TXD
constexpr PinId kCanRxd = Pin('A', 11);  // and RXD

// The world's own cadence while TIM1 is not counting (before the firmware starts it,
// after a reset): the plant keeps moving, its motor unpowered.
constexpr Picoseconds kIdleStep = 100 * kPsPerSecond / 1'000'000;
// The world's service: the link, the pacing, the owner's requests. Once a millisecond
// of virtual time: each read of a SocketCAN socket and of the clock is a system call,
// costly under emulation (mjc sim polls at the same rate for the same reason); a frame
// from the host waits at most this long.
constexpr Picoseconds kServicePeriod = kPsPerSecond / 1000;
// Frames taken from the link per service: a burst the bus delivers back to back. More
// wait in the socket (which counts what it drops) until these are through.
constexpr int kBurst = 64;
// A stopping board handles what it was sent: it runs this long after the link is
// empty (two passes of its main loop's 1 ms cadences at least).
constexpr Picoseconds kDrainTime = 3 * kServicePeriod;

// The plant's AS5047P frame (datasheet read frame: bit 15 even parity, bit 14 EF,
// 13:0 the angle) as what the sensor model answers: the angle, the error flag, and a
// parity the plant corrupted (an injected line fault).
g474model::AngleSample JointSample(std::uint16_t frame) {
  g474model::AngleSample s;
  s.count = static_cast<std::uint16_t>(frame & 0x3FFFu);
  s.error_flag = (frame & 0x4000u) != 0;
  s.corrupt_parity = g474model::OddBitCount(frame);
  return s;
}

// The time a frame occupies the bus at the controller's bit rates (ISO 11898-1 frame
// layout with a standard identifier; stuff bits not counted, as in the FDCAN model).
// A burst from the link reaches the controller frame by frame at this pace.
Picoseconds BusTime(const g474model::CanBusFrame& f, double nominal, double data) {
  if (nominal <= 0) nominal = 1e6;  // not configured yet: nothing is heard anyway
  if (data <= 0) data = nominal;
  double arbitration_bits = 0, data_bits = 0;
  if (!f.fd) {
    arbitration_bits = 47 + 8.0 * f.length;  // SOF..EOF and the intermission
  } else {
    // SOF, identifier, RRS, IDE, FDF, res, BRS | ESI, DLC, data, stuff count, CRC
    // (17 or 21 bits), CRC delimiter | ACK, EOF, intermission.
    arbitration_bits = 16 + 13;
    data_bits = 1 + 4 + 8.0 * f.length + 4 + (f.length > 16 ? 21 : 17) + 1;
    if (!f.brs) arbitration_bits += data_bits, data_bits = 0;
  }
  const double seconds = arbitration_bits / nominal + data_bits / data;
  return static_cast<Picoseconds>(seconds * static_cast<double>(kPsPerSecond));
}

}  // namespace

VirtualBoard::VirtualBoard(const VirtualBoardConfig& config, host::CanLink* link)
    : config_(config), link_(link) {
  // The FLASH model keeps a file of exactly its array's size, or the array and its
  // option bytes' block (and leaves any other alone): a file it cannot keep is refused
  // here, rather than a board that forgets.
  if (!config_.flash_path.empty() && std::filesystem::exists(config_.flash_path)) {
    std::error_code error;
    const std::uintmax_t size = std::filesystem::file_size(config_.flash_path, error);
    if (error || (size != g474model::Flash::kSize &&
                  size != g474model::Flash::kSize + g474model::OptionBytes::kFileBytes)) {
      throw std::runtime_error(
          config_.flash_path + ": " +
          (error ? error.message()
                 : std::to_string(size) + " bytes, not a G474 flash file (" +
                       std::to_string(g474model::Flash::kSize) + " bytes, or " +
                       std::to_string(g474model::Flash::kSize +
                                      g474model::OptionBytes::kFileBytes) +
                       " with its option bytes)") +
          "; left as it is");
    }
  }
  g474model::ChipConfig chip;
  chip.rcc.hse_hz = kCrystalHz;
  chip.flash.path = config_.flash_path;
  chip.boot0 = config_.boot0;
  std::copy(config_.unique_id.begin(), config_.unique_id.end(), chip.flash.uid);
  chip_ = std::make_unique<g474model::VirtualChip>(chip);
  if (!config_.flash_path.empty() && !chip_->flash().mirrored()) {
    throw std::runtime_error(config_.flash_path + ": cannot open it for writing");
  }
  plant_ = std::make_unique<plant::Plant>(config_.plant);
  last_motor_count_ = plant_->MotorCount();

  // The image's vector table, as the chip's handlers: each entry on its IRQ line. The
  // tick's entry is counted: the firmware's board in RAM is the one this start built
  // only once its tick has run (Run() enables the tick after building it; until then
  // board::Instance() may be the one from before a reset, which nothing zeroes here).
  for (const auto& entry : board::kDriverIrqs) {
    if (entry.irq == stm32g4::irq::kTim1Update) {
      chip_->SetHandler(entry.irq, [this, handler = entry.handler] {
        ++ticks_since_start_;
        handler();
      });
    } else {
      chip_->SetHandler(entry.irq, entry.handler);
    }
  }
  // The NMI as the image's NmiHandler takes it (startup.cc): a flash ECC double error
  // recorded by the flash driver (the model raises no other NMI).
  chip_->SetNmiHandler([] { (void)stm32g4::HandleFlashEccNmi(); });
  chip_->AttachEncoder(kEncoderA, kEncoderB);
  chip_->AttachAs5047p(kJointEncoder).SetAngleSource([this] {
    return JointSample(plant_->JointFrame());
  });
  chip_->AttachCanTransceiver(kCanTxd, kCanRxd);
  chip_->fdcan1().SetTransmitHook(
      [this](const g474model::CanBusFrame& f, Picoseconds) { OnTransmit(f); });
  chip_->Schedule(0, [this] { StepEvent(); });
  chip_->Schedule(kServicePeriod, [this] { ServiceEvent(); });
  stm32g4::BindRegisterSpace(chip_.get());
}

VirtualBoard::~VirtualBoard() {
  Stop();
  stm32g4::BindRegisterSpace(nullptr);
}

double VirtualBoard::Seconds(Picoseconds t) const {
  return static_cast<double>(t) / static_cast<double>(kPsPerSecond);
}

void VirtualBoard::Say(const char* format, ...) {
  if (config_.log == nullptr) return;
  char line[512];
  va_list args;
  va_start(args, format);
  std::vsnprintf(line, sizeof line, format, args);
  va_end(args);
  std::fprintf(config_.log, "%s: %s\n", config_.name.c_str(), line);
  std::fflush(config_.log);
}

// ── The world ─────────────────────────────────────────────────────────────────────

void VirtualBoard::StepEvent() {
  const Picoseconds now = chip_->now();
  // What drove the bridge since the last step: the duty the timer's outputs took at
  // that step's update event (the compare registers are preloaded: a duty written by
  // a tick takes effect at the next update), and the enable line as the tick after it
  // left it (a plain output: in effect at once, a microsecond into the interval).
  const g474model::BridgeDrive drive =
      chip_->HBridge(kBridgeIn1, kBridgeIn2, kBridgeEnable);
  if (now > last_step_) {
    // The plant takes steps of at most 10 ms (its limit); the world's are 100 µs.
    for (double left = Seconds(now - last_step_); left > 0; left -= 0.01) {
      plant_->Step(duty_, drive.enabled, std::min(left, 0.01));
    }
    last_step_ = now;
    const std::uint16_t count = plant_->MotorCount();
    motor_position_ += static_cast<std::int16_t>(count - last_motor_count_);
    last_motor_count_ = count;
    chip_->MoveEncoder(motor_position_);
  }
  duty_ = drive.duty;  // loaded at this update: driven until the next one
  if (step_observer_) {
    const app::JointBoard* fw = Booted();
    step_observer_(*plant_, fw == nullptr ? 0 : fw->app().last().telemetry.tick + 1);
  }
  // The next update event of TIM1 (the next change of the duty it outputs, and the
  // next tick): the plant is stepped there, before the interrupt is taken.
  Picoseconds next = chip_->tim1().NextUpdate();
  if (next == g474model::kNever || next <= now) next = now + kIdleStep;
  chip_->Schedule(next, [this] { StepEvent(); });
}

void VirtualBoard::OnTransmit(const g474model::CanBusFrame& f) {
  if (link_ == nullptr) return;
  protocol::CanFrame frame;
  frame.id = f.id;
  frame.fd = f.fd;
  frame.length = std::min<std::uint8_t>(f.length, 64);
  std::copy_n(f.data.begin(), frame.length, frame.data.begin());
  std::string why;
  // The link already waited for room: the frame is lost, counted, as a controller's
  // frame that never gets on the bus.
  if (!link_->Send(frame, &why)) ++send_failures_;
}

void VirtualBoard::PollLink() {
  if (link_ == nullptr || !to_deliver_.empty()) return;
  link_busy_ = false;
  for (int i = 0; i < kBurst; ++i) {
    std::string why;
    const host::ReceiveResult r = link_->Receive(0, &why);
    if (r.status == host::ReceiveStatus::kError) {
      throw std::runtime_error(config_.iface + ": " + why);
    }
    // Down: the socket stays bound, frames come once it is up again (the link keeps
    // the state, Report says it).
    if (!r) break;
    g474model::CanBusFrame f;
    f.id = r->frame.id;
    f.fd = r->frame.fd || r->flags != 0;
    f.brs = (r->flags & 0x01u) != 0;  // CANFD_BRS
    f.length = r->frame.length;
    f.dlc = g474model::LengthToDlc(f.length);
    std::copy_n(r->frame.data.begin(), f.length, f.data.begin());
    to_deliver_.push_back(f);
    link_busy_ = true;
  }
  // A bus-off error frame on the link stands for the controller's own bus-off.
  for (; bus_off_seen_ < link_->stats().bus_off; ++bus_off_seen_) {
    chip_->fdcan1().InjectBusOff();
  }
  if (!to_deliver_.empty()) DeliverNext();
}

void VirtualBoard::DeliverNext() {
  const g474model::CanBusFrame f = to_deliver_.front();
  to_deliver_.pop_front();
  if (chip_->DeliverCanFrame(f)) {
    ++frames_delivered_;
  } else {
    ++frames_unheard_;  // the controller was not on the bus (INIT, bus-off)
  }
  if (!to_deliver_.empty()) {
    const Picoseconds gap =
        BusTime(to_deliver_.front(), chip_->fdcan1().nominal_bitrate(),
                chip_->fdcan1().data_bitrate());
    chip_->Schedule(chip_->now() + gap, [this] { DeliverNext(); });
  }
}

void VirtualBoard::Pace() {
  if (config_.speed <= 0) return;
  using Clock = std::chrono::steady_clock;
  const double ahead_s = Seconds(chip_->now() - origin_virtual_) / config_.speed;
  const auto due = origin_ + std::chrono::duration_cast<Clock::duration>(
                                 std::chrono::duration<double>(ahead_s));
  const auto now = Clock::now();
  if (now - due > std::chrono::milliseconds(20)) {
    // Behind: no racing to catch up (a burst of board time between two of a host's
    // heartbeats would look like a silent host); the origin moves instead.
    behind_s_ += std::chrono::duration<double>(now - due).count();
    origin_ = now;
    origin_virtual_ = chip_->now();
    if (!warned_speed_) {
      warned_speed_ = true;
      Say("cannot keep --speed %g on this machine: the board runs at its own slower "
          "pace (the summary says how slow)",
          config_.speed);
    }
  } else if (due - now > std::chrono::milliseconds(20)) {
    // Sleeps only once 20 ms of lead have built up, as mjc sim does: under emulation
    // sleeping and waking cost more than simulating.
    std::this_thread::sleep_until(due);
  }
}

void VirtualBoard::DrainViolations() {
  g474model::ViolationLog& log = chip_->violations();
  if (log.empty()) return;
  for (const g474model::Violation& v : log.entries()) {
    // Printed once per distinct rule and text; all kept (a run with any fails).
    if (said_violations_.size() < 64 &&
        said_violations_.insert(v.source + v.what).second) {
      Say("model violation at %.6f s: %s: %s", Seconds(v.time_ps), v.source.c_str(),
          v.what.c_str());
    }
    if (violations_.size() < 10000) violations_.push_back(v);
  }
  total_violations_ += log.entries().size();
  log.Clear();
}

const app::JointBoard* VirtualBoard::Booted() const {
  return ticks_since_start_ == 0 ? nullptr : board::Instance();
}

void VirtualBoard::Report() {
  const app::JointBoard* fw = Booted();
  if (fw == nullptr || fw->app().last().telemetry.tick == 0) return;
  if (!boot_reported_) {
    boot_reported_ = true;
    const board::BootFacts& boot = board::LastBoot();
    if (boot.calibration_restored) {
      Say("restored calibration #%u from flash", boot.calibration_sequence);
    } else {
      Say("no stored calibration: uncalibrated");
    }
    if (!announced_) {
      announced_ = true;
      // The node id the firmware runs with: an identity record in the flash file wins
      // over the command line's.
      Say("node %d on %s (%s)", fw->node().config().node, config_.iface.c_str(),
          config_.description.c_str());
    }
  }
  if (link_ != nullptr && link_->stats().went_down != downs_reported_) {
    downs_reported_ = link_->stats().went_down;
    up_reported_ = false;
    Say("%s went down at %.4f s: the board goes on without its bus",
        config_.iface.c_str(), Seconds(chip_->now()));
  }
  if (!up_reported_ && link_ != nullptr && !link_->down()) {
    up_reported_ = true;
    Say("%s is up again at %.4f s", config_.iface.c_str(), Seconds(chip_->now()));
  }
  for (; bus_off_reported_ < fw->node().counters().bus_off; ++bus_off_reported_) {
    Say("%s: bus-off at %.4f s: motor stopped (fault 303) until the host clears it",
        config_.iface.c_str(), Seconds(chip_->now()));
  }
}

void VirtualBoard::ServiceEvent() {
  const Picoseconds now = chip_->now();
  // The next one first: a request below may reset the chip (the world's schedule
  // goes on across resets).
  chip_->Schedule(now + kServicePeriod, [this] { ServiceEvent(); });
  DrainViolations();
  Report();
  if (const int request = joint_error_request_.exchange(0); request != 0) {
    if (request > 0) {
      plant_->InjectFault({plant::SensorFaultKind::kJointErrorFlag, 0, 0});
    } else {
      plant_->ClearFaults();
    }
    Say("joint encoder error flag %s at %.4f s", request > 0 ? "raised" : "cleared",
        Seconds(now));
  }
  std::vector<std::function<void()>> posted;
  {
    std::lock_guard lock(mutex_);
    posted.swap(posted_);
  }
  for (auto& fn : posted) fn();
  PollLink();
  Pace();
  Checkpoint(false);
}

void VirtualBoard::Checkpoint(bool halt_here) {
  std::unique_lock lock(mutex_);
  const Picoseconds now = chip_->now();
  if (stop_requested_ || (config_.stop != nullptr && config_.stop->load()) ||
      (config_.seconds > 0 && Seconds(now) >= config_.seconds)) {
    draining_ = true;
  }
  if ((halt_here || halt_requested_) && !draining_) {
    halt_requested_ = false;
    DrainViolations();
    mode_ = Mode::kHalted;
    changed_.notify_all();
    changed_.wait(lock, [this] { return mode_ != Mode::kHalted; });
    // Wall time spent halted is no delay of the board's.
    origin_ = std::chrono::steady_clock::now();
    origin_virtual_ = chip_->now();
    if (stop_requested_) draining_ = true;
  }
  if (!draining_) return;
  if (!to_deliver_.empty() || link_busy_) {
    drained_at_ = 0;
    return;
  }
  if (drained_at_ == 0) drained_at_ = now;
  if (now - drained_at_ >= kDrainTime) throw Stopped{};
}

// ── The firmware's thread ─────────────────────────────────────────────────────────

void VirtualBoard::FirmwareThread() {
  started_ = origin_ = std::chrono::steady_clock::now();
  origin_virtual_ = chip_->now();
  board::RunOptions options;
  options.node = config_.node;
  // A host's heartbeats come every 100 ms of wall time, `speed` times as much board
  // time: the supervision timeout scales with it (as mjc sim's), and is off at speed
  // 0, where wall time means nothing to the board.
  const std::uint16_t timeout = app::CanNodeConfig{}.host_timeout_ms;
  options.host_timeout_ms = config_.speed == 0
                                ? std::uint16_t{0}
                                : static_cast<std::uint16_t>(std::clamp(
                                      std::lround(timeout * config_.speed), 1L, 60000L));
  for (;;) {
    try {
      if (chip_->boot_source() != g474model::BootSource::kMainFlash) {
        // The option bytes and PB8 chose other code (RM0440 §2.6): none of ours runs,
        // and ST's ROM bootloader has no FDCAN on the G47x: the board is silent until
        // a reset boots it elsewhere.
        Say("boots %s (FLASH_OPTR 0x%08X): no image runs, silent on the bus",
            g474model::BootSourceName(chip_->boot_source()),
            chip_->flash().options().loaded());
        chip_->RunWithoutImage();
        break;
      }
      // The image's entry after its memory initialisation (startup.cc).
      board::BringUp();
      board::Run(options);
    } catch (const g474model::ChipReset& reset) {
      ++resets_;
      ticks_since_start_ = 0;
      boot_reported_ = false;
      bus_off_reported_ = 0;
      Say("reset (%s) at %.4f s: the firmware starts again from its entry",
          g474model::ResetCauseName(reset.cause), Seconds(chip_->now()));
      continue;
    } catch (const Stopped&) {
    } catch (const std::exception& e) {
      std::lock_guard lock(mutex_);
      error_ = e.what();
      Say("stopped: %s", e.what());
    }
    break;
  }
  DrainViolations();
  std::lock_guard lock(mutex_);
  wall_s_ =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - started_).count();
  mode_ = Mode::kDone;
  changed_.notify_all();
}

// ── Control ───────────────────────────────────────────────────────────────────────

void VirtualBoard::RunUntil(double t_s) {
  Halt();
  {
    std::lock_guard lock(mutex_);
    if (mode_ == Mode::kDone) return;
  }
  // Halted or not started: the board's thread is not running, the schedule is ours.
  const auto at = static_cast<Picoseconds>(std::llround(t_s * 1e12));
  chip_->Schedule(std::max(at, chip_->now()), [this] { Checkpoint(true); });
  Resume();
  std::unique_lock lock(mutex_);
  changed_.wait(lock, [this] { return mode_ == Mode::kHalted || mode_ == Mode::kDone; });
}

void VirtualBoard::Resume() {
  std::unique_lock lock(mutex_);
  if (mode_ == Mode::kIdle) {
    mode_ = Mode::kRunning;
    thread_ = std::thread([this] { FirmwareThread(); });
  } else if (mode_ == Mode::kHalted) {
    mode_ = Mode::kRunning;
    changed_.notify_all();
  }
}

void VirtualBoard::Halt() {
  std::unique_lock lock(mutex_);
  if (mode_ != Mode::kRunning) return;
  halt_requested_ = true;
  changed_.wait(lock, [this] { return mode_ == Mode::kHalted || mode_ == Mode::kDone; });
}

void VirtualBoard::Stop() {
  {
    std::unique_lock lock(mutex_);
    stop_requested_ = true;
    if (mode_ == Mode::kIdle) mode_ = Mode::kDone;
    if (mode_ == Mode::kHalted) {
      mode_ = Mode::kRunning;
      changed_.notify_all();
    }
  }
  if (thread_.joinable()) thread_.join();
}

void VirtualBoard::Wait() {
  if (thread_.joinable()) thread_.join();
}

void VirtualBoard::Post(std::function<void()> fn) {
  std::lock_guard lock(mutex_);
  posted_.push_back(std::move(fn));
}

// ── Views ─────────────────────────────────────────────────────────────────────────

const app::JointBoard* VirtualBoard::firmware() const { return Booted(); }

double VirtualBoard::now_s() const { return Seconds(chip_->now()); }

bool VirtualBoard::halted() const {
  std::lock_guard lock(mutex_);
  return mode_ == Mode::kHalted;
}

bool VirtualBoard::stopped() const {
  std::lock_guard lock(mutex_);
  return mode_ == Mode::kDone;
}

VirtualBoardSummary VirtualBoard::Summary() const {
  VirtualBoardSummary s;
  s.simulated_s = Seconds(chip_->now());
  s.wall_s = wall_s_;
  s.behind_s = behind_s_;
  if (link_ != nullptr) {
    s.frames_sent = link_->stats().sent;
    s.rx_dropped = link_->stats().rx_dropped;
  }
  s.send_failures = send_failures_;
  s.frames_delivered = frames_delivered_;
  s.frames_unheard = frames_unheard_;
  if (const app::JointBoard* fw = Booted()) s.counters = fw->node().counters();
  s.resets = resets_;
  s.violations = total_violations_;
  s.error = error_;
  return s;
}

std::string VirtualBoard::SummaryLine() const {
  const VirtualBoardSummary s = Summary();
  const app::CanNodeCounters& c = s.counters;
  char line[512];
  std::snprintf(
      line, sizeof line,
      "%.1f s simulated; frames sent %llu (send failures %llu), handled %u, ignored %u, "
      "malformed %u, rx dropped %llu, tx dropped %u, bus-off %u",
      s.simulated_s, static_cast<unsigned long long>(s.frames_sent),
      static_cast<unsigned long long>(s.send_failures), c.handled, c.ignored,
      std::accumulate(c.malformed.begin(), c.malformed.end(), 0u),
      static_cast<unsigned long long>(s.rx_dropped), c.tx_dropped, c.bus_off);
  return line;
}

}  // namespace mjc::g474board
