// The virtual joint board: the image's own code (firmware/boards/g474_joint: the start-up
// report and clock bring-up, board::Run(), the interrupt entries, the drivers, the
// application) built for x86 and run against the register models of the STM32G474
// (sim_host/g474), with the board around the chip simulated:
//
//   chip                      world (this class)
//   TIM1 CH1/CH2 + PB10  ───▶ the H-bridge: the plant's motor steps under the drive the
//                              timer and the enable pin put out (VirtualChip::HBridge)
//   TIM3 CH1/CH2 (PC6/7) ◀─── the motor's quadrature encoder follows the plant's motor
//   SPI1 + PA4 (AS5047P) ◀─── the joint encoder's angle is the plant's joint frame (its
//                              injected sensor faults included)
//   FDCAN1 (PA11/PA12)   ◀──▶ a host::CanLink: SocketCAN (mjc-g474) or the in-process
//                              bus of the tests; a bus-off error frame on the link is
//                              the controller's own bus-off
//   FLASH                     the calibration pages, optionally kept in a file
//
// Time. The chip's virtual time runs as the firmware accesses registers and sleeps
// (VirtualChip). The plant steps at every update event of TIM1 — when the PWM's
// preloaded duty takes effect and the tick's interrupt is raised — over the interval
// since the last one, under the drive of that interval: the duty the timer's outputs
// took at its start, the enable line as the tick then left it. The step comes before
// the interrupt at the same instant, so the tick samples the plant as it is then. Once a
// millisecond of virtual time the board services the world: frames from the link, the
// pacing against wall time (at most `speed`, never racing to catch up), requests from
// its owner.
//
// Resets. An IWDG expiry, AIRCR.SYSRESETREQ or a power cut resets the models (the flash
// array is kept) and unwinds the firmware (VirtualChip::ChipReset); the board then runs
// it again from its entry, BringUp() and Run(), which rebuild its RAM state. The world
// goes on: the plant, the link, the schedule.
//
// Threads. The firmware runs in a thread of its own; the owner runs it to a point of
// virtual time (RunUntil, then it halts), lets it run (Resume), halts it (Halt) or ends
// it (Stop). The chip, the plant and the firmware's RAM may be read only while the
// board is halted or stopped. One virtual board per process: the register space the
// drivers reach and the firmware's statics are the process's.
//
// Every model violation (VirtualChip::violations()) is printed once as it appears and
// kept: a run with any is a failed run (mjc-g474 exits 1).
#pragma once

#include <array>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <cstdio>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "mjc/app/joint_board.h"
#include "mjc/g474model/virtual_chip.h"
#include "mjc/host/can_link.h"
#include "mjc/plant/plant.h"

namespace mjc::g474board {

struct VirtualBoardConfig {
  plant::PlantParams plant;
  std::uint8_t node = 1;  // when the flash holds no identity record (RunOptions::node)
  // The FLASH model's array is loaded from and saved to this file ("" = none; created
  // when missing): the calibration survives a restart of the program. An existing file
  // of another size is refused (the constructor throws), never overwritten.
  std::string flash_path;
  // The chip's unique device ID (RM0440 §48.1), three words as the factory wrote them.
  std::array<std::uint32_t, 3> unique_id = {0x00400031u, 0x4E4B5003u, 0x20343736u};
  // What the board puts on PB8-BOOT0 (docs/BRINGUP.md: a pull-down). With the factory
  // option bytes the pin decides the boot: pulled up, the chip starts ST's ROM
  // bootloader and runs none of the firmware.
  g474model::Boot0Pin boot0 = g474model::Boot0Pin::kPulledDown;
  // Virtual seconds per wall second; 0: as fast as the machine runs it.
  double speed = 1;
  // The run ends (after delivering what the link holds) once this much virtual time
  // has passed (0: never) or when *stop turns true (checked every millisecond).
  double seconds = 0;
  const std::atomic<bool>* stop = nullptr;
  // Messages ("<name>: ..."), nullptr: quiet. `iface` names the link in them.
  std::FILE* log = stderr;
  std::string name = "mjc-g474";
  std::string iface = "vcan0";
  std::string description;  // "(default, robot alone)" in the start line
};

// What a run did, for the summary line and the tests.
struct VirtualBoardSummary {
  double simulated_s = 0;
  double wall_s = 0;
  double behind_s = 0;  // wall time the board fell behind its speed, in all
  std::uint64_t frames_sent = 0, send_failures = 0, rx_dropped = 0;
  std::uint64_t frames_delivered = 0, frames_unheard = 0;
  app::CanNodeCounters counters;
  int resets = 0;
  std::size_t violations = 0;
  std::string error;  // the firmware thread ended on an unexpected exception
};

class VirtualBoard {
 public:
  // `link` (may be null: no bus) must outlive the board. Builds the chip (its clocks,
  // its flash from the file) and the plant; the firmware starts at the first RunUntil
  // or Resume, from power-on. Throws std::runtime_error, saying why, when the flash
  // file cannot be used.
  VirtualBoard(const VirtualBoardConfig& config, host::CanLink* link);
  ~VirtualBoard();
  VirtualBoard(const VirtualBoard&) = delete;
  VirtualBoard& operator=(const VirtualBoard&) = delete;

  // ── Control (the owner's thread) ──────────────────────────────────────────────
  // Runs until virtual time `t_s`, then halts; returns once halted (or stopped).
  void RunUntil(double t_s);
  // Runs on until Halt, Stop, the configured seconds or stop flag.
  void Resume();
  // Halts at the next millisecond of virtual time; returns once halted.
  void Halt();
  // Ends the run: what the link holds is delivered and handled first. Idempotent.
  void Stop();
  // Waits until the run has ended by itself (seconds, stop flag) and returns.
  void Wait();
  // `fn` runs in the board's thread at its next millisecond of virtual time, between
  // the firmware's register accesses (the world's side: cut the power, inject a
  // sensor fault). Takes effect when the board runs.
  void Post(std::function<void()> fn);
  // The plant's joint encoder flags an error (EF) until cleared. Any thread (a signal
  // handler's flag is turned into this by the owner).
  void SetJointError(bool on) { joint_error_request_ = on ? 1 : -1; }
  // Called after every plant step with the plant and the tick number the firmware's
  // next tick will carry (that tick samples the plant as it is now). Before the run.
  void SetStepObserver(std::function<void(const plant::Plant&, std::uint32_t)> fn) {
    step_observer_ = std::move(fn);
  }

  // ── Views (only while halted or stopped) ──────────────────────────────────────
  g474model::VirtualChip& chip() { return *chip_; }
  plant::Plant& plant() { return *plant_; }
  // The firmware's board in its RAM (nullptr before this start's first tick).
  const app::JointBoard* firmware() const;
  double now_s() const;
  // Every violation the run has seen, in order (the chip's log is drained into it).
  const std::vector<g474model::Violation>& violations() const { return violations_; }
  bool halted() const;
  bool stopped() const;
  VirtualBoardSummary Summary() const;
  // The summary line mjc sim also prints.
  std::string SummaryLine() const;

 private:
  struct Stopped {};
  enum class Mode : std::uint8_t { kIdle, kRunning, kHalted, kStopping, kDone };

  void FirmwareThread();
  void StepEvent();
  void ServiceEvent();
  void Checkpoint(bool halt_here);
  void Pace();
  void PollLink();
  void DeliverNext();
  void OnTransmit(const g474model::CanBusFrame& frame);
  void DrainViolations();
  void Report();
  // The firmware's board once this start's tick has run, else nullptr.
  const app::JointBoard* Booted() const;
  void Say(const char* format, ...) __attribute__((format(printf, 2, 3)));
  double Seconds(g474model::Picoseconds t) const;

  VirtualBoardConfig config_;
  host::CanLink* link_;
  std::unique_ptr<g474model::VirtualChip> chip_;
  std::unique_ptr<plant::Plant> plant_;

  // The world's state (the board's thread only).
  g474model::Picoseconds last_step_ = 0;
  double duty_ = 0;  // what the bridge's legs drive since the last update event
  std::uint16_t last_motor_count_ = 0;
  std::int64_t motor_position_ = 0;  // unwrapped counts since power-on
  std::deque<g474model::CanBusFrame> to_deliver_;
  bool link_busy_ = false;  // the last poll took frames: there may be more
  std::uint64_t bus_off_seen_ = 0;
  bool draining_ = false;
  g474model::Picoseconds drained_at_ = 0;
  std::uint64_t frames_delivered_ = 0, frames_unheard_ = 0, send_failures_ = 0;
  std::set<std::string> said_violations_;
  std::size_t total_violations_ = 0;
  bool announced_ = false;
  bool boot_reported_ = false;
  std::uint32_t bus_off_reported_ = 0;
  // The interface going down and up again (the link counts the outages and keeps the
  // state): the board rides through without its bus and says each, even when both
  // fall between two reports.
  bool up_reported_ = true;
  std::uint64_t downs_reported_ = 0;
  int resets_ = 0;
  std::uint64_t ticks_since_start_ = 0;  // tick interrupts since the last (re)start
  std::function<void(const plant::Plant&, std::uint32_t)> step_observer_;
  std::atomic<int> joint_error_request_{0};
  // Pacing.
  std::chrono::steady_clock::time_point started_, origin_;
  g474model::Picoseconds origin_virtual_ = 0;
  double behind_s_ = 0;
  bool warned_speed_ = false;

  // Owner ↔ board.
  mutable std::mutex mutex_;
  std::condition_variable changed_;
  Mode mode_ = Mode::kIdle;
  bool halt_requested_ = false;
  bool stop_requested_ = false;
  std::vector<std::function<void()>> posted_;
  std::thread thread_;
  std::vector<g474model::Violation> violations_;
  std::string error_;
  double wall_s_ = 0;
};

}  // namespace mjc::g474board
