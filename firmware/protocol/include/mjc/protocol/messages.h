// The joint board's CAN messages: the single source of truth. Each message is a struct
// (the values, in the firmware's own types) and a Message<> specialisation (function
// code, length, sender, and the signal list placing each field in the payload). The
// codec (codec.h) and the DBC file (host_tools: mjc-dbc, maestro_jc.dbc) are derived
// from these lists and nothing else.
//
// Wire rules: every frame fits classical CAN (≤ 8 bytes), except the FD-only batch of
// angle samples (TelemetryAngleBatch, 48 bytes) that a board on a CAN FD link sends in
// place of TelemetryAngles; little-endian signals;
// fixed-point fields travel as their raw Q-format integers (DBC factor 2^-F), so the
// board never converts and host and board agree bit for bit; enums travel as their
// stable numbers and unknown values are refused on decode.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <tuple>

#include "mjc/core/interface_energy.h"
#include "mjc/core/quantities.h"
#include "mjc/core/supervisor.h"
#include "mjc/core/trajectory.h"
#include "mjc/protocol/params.h"
#include "mjc/protocol/signal.h"
#include "mjc/protocol/states.h"

// Enum values accepted from the bus, in each enum's own namespace (argument-dependent
// lookup finds them).
namespace mjc {

constexpr bool ValidEnumValue(Fault f) {
  switch (f) {
    case Fault::kNone:
    case Fault::kJointParity:
    case Fault::kJointErrorFlag:
    case Fault::kJointJump:
    case Fault::kJointStuck:
    case Fault::kMotorStuck:
    case Fault::kJointAngleLimit:
    case Fault::kMotorAngleLimit:
    case Fault::kTorqueLimit:
    case Fault::kVelocityLimit:
    case Fault::kTickOverrun:
    case Fault::kCommandTimeout:
    case Fault::kHostHeartbeatLost:
    case Fault::kCanBusOff:
    case Fault::kBoardStartup:
    case Fault::kEmergencyStop:
      return true;
  }
  return false;
}
constexpr bool ValidEnumValue(Segment s) { return static_cast<std::uint8_t>(s) <= 7; }
constexpr bool ValidEnumValue(InterfaceFitStatus s) {
  return static_cast<std::uint8_t>(s) <= 5;
}
constexpr bool ValidEnumValue(Motion m) {
  return m == Motion::kFlexion || m == Motion::kExtension;
}

}  // namespace mjc

namespace mjc::protocol {

// Function codes, 7 bits, ordered by urgency (lower wins arbitration). Stable: never
// renumber.
enum class Function : std::uint8_t {
  // To every node at once (node 0): identifier 0x000, which wins arbitration against
  // every other frame on the bus.
  kStopAll = 0x00,
  kFault = 0x01,
  kCommand = 0x02,
  kSetpoint = 0x03,
  kCommandResult = 0x04,
  kTrialConfig = 0x05,
  kSweepConfig = 0x06,
  kWindowStart = 0x07,
  kWindowHeader = 0x08,
  kWindowEnergy = 0x09,
  kWindowWork = 0x0A,
  kWindowPeaks = 0x0B,
  kWindowTicks = 0x0C,
  kWindowFit = 0x0D,
  kWindowFitResidual = 0x0E,
  kMotionConfig = 0x0F,  // board → host: the motion that started and what it runs
  kParamWrite = 0x10,
  kParamRead = 0x11,
  kParamValue = 0x12,
  kTelemetryAngles = 0x20,
  kTelemetryTorque = 0x21,
  kTelemetryPower = 0x22,
  kTelemetryEnergy = 0x23,
  kTelemetryControl = 0x24,
  kTelemetryAngleBatch = 0x25,  // CAN FD only: TelemetryAngles, several samples a frame
  kHeartbeat = 0x30,
  kHostHeartbeat = 0x31,
  kBoardInfo = 0x32,
  kChipInfo = 0x33,  // bootloader → host: option bytes, clock source, reset flags
  // The bootloader (firmware/bootloader/BOOTLOADER.md).
  kBootStatus = 0x38,          // bootloader → host: its state, why it stays, progress
  kBootHold = 0x39,            // host → board: stay in (or enter) the bootloader
  kBootCommand = 0x3A,         // host → bootloader: commit, boot, abort
  kBootResult = 0x3B,          // bootloader → host: the outcome of a request
  kBootIsoTpToBoard = 0x3C,    // ISO-TP host → bootloader: begin (the header), chunks
  kBootIsoTpFromBoard = 0x3D,  // ISO-TP bootloader → host (flow control)
  kIsoTpToBoard = 0x3E,        // ISO-TP channel host → board (calibration records)
  kIsoTpFromBoard = 0x3F,      // ISO-TP channel board → host
};

enum class Sender : std::uint8_t { kBoard, kHost };

enum class CommandCode : std::uint8_t {
  kStop = 1,
  kClearFaults = 2,
  kStartTrial = 3,   // with the last TrialConfig, if it is the one the command names
  kStartSweep = 4,   // with the last SweepConfig, if it is the one the command names
  kStartStream = 5,  // streamed setpoints from the present position
};
constexpr bool ValidEnumValue(CommandCode c) {
  return static_cast<std::uint8_t>(c) >= 1 && static_cast<std::uint8_t>(c) <= 5;
}

// Which image answers: the application, or the bootloader that stays when there is no
// valid application or the host asked it to.
enum class ImageKind : std::uint8_t { kApplication = 0, kBootloader = 1 };
constexpr bool ValidEnumValue(ImageKind k) { return static_cast<std::uint8_t>(k) <= 1; }

// Why the board last started (its reset controller's flags; the board maps its chip's
// flags to these numbers).
enum class ResetCause : std::uint8_t {
  kUnknown = 0,
  kPowerOn = 1,
  kPin = 2,       // the reset line (a host's reset line, or the button)
  kSoftware = 3,  // the firmware asked for it (e.g. to enter the bootloader)
  kWatchdog = 4,  // the independent watchdog: the main loop stopped making progress
  kOther = 5,
};
constexpr bool ValidEnumValue(ResetCause c) { return static_cast<std::uint8_t>(c) <= 5; }

enum class ParamStatus : std::uint8_t {
  kOk = 0,
  kUnknown = 1,
  kOutOfRange = 2,
  kRefusedNotIdle = 3,
  kReadOnly = 4,
  kRefusedBusy = 5,  // an earlier write or calibration is still being applied: retry
  // A write outside the bound of a protection, refused; the answer's value is the bound
  // (the parameter keeps its value: a read tells it).
  kBelowMinimum = 6,      // below the list's minimum (protocol/params.h)
  kAboveMaximum = 7,      // above the list's maximum: the image's ceiling
  kBeyondJointLimit = 8,  // looser than the joint's limit the board holds (its
                          // description's, or the limit itself loosened: only a reset)
};
constexpr bool ValidEnumValue(ParamStatus s) { return static_cast<std::uint8_t>(s) <= 8; }

// Energies travel in Q7.24 J (±128 J, 0.06 µJ): a window's energy is millijoules.
using WireEnergy = Fixed<Joule, 24>;

// --- the messages ------------------------------------------------------------------

struct FaultEvent {
  Fault fault = Fault::kNone;
  std::uint32_t tick = 0;
  BoardState state = BoardState::kFault;
};
// A host session: one running tool (mjc trial, calibrate, monitor…), named by a random
// non-zero number it picks at start. A motion is supervised by the heartbeats of the
// session that started it, and only those (CanNode): another tool's heartbeats cannot
// keep a motion going whose commander died. 0 = no session (a tool that sends no
// heartbeats, e.g. cansend): its motions are not supervised.
using SessionId = std::uint16_t;

// A motion's configuration by name: the CRC-32 of the TrialConfig or SweepConfig
// payload as encoded (ConfigDigestOf, codec.h). A configuration frame carries no sender,
// so the board cannot tell whose it holds; the start names the configuration its
// session sent instead, and the board starts only when the one it holds is that one —
// any other sender's frame since, or a changed one, makes the start a refusal
// (kDetailConfigMismatch). What runs is then reported under the same name
// (MotionConfig, WindowStart) for the host to check before it records anything.
using ConfigDigest = std::uint32_t;

// kRefusedInvalid's detail for a start whose config digest is not that of the
// configuration the board holds (another sender's came since, or none was sent).
inline constexpr std::uint8_t kDetailConfigMismatch = 65;

struct Command {
  CommandCode code = CommandCode::kStop;
  std::uint8_t sequence = 0;
  SessionId session = 0;  // who commands: binds a started motion to its heartbeats
  // kStartTrial, kStartSweep: the digest of the configuration this session sent (the
  // board refuses the start unless it holds that one); 0 and unused otherwise.
  ConfigDigest config = 0;
};
struct Setpoint {
  Angle position;
  std::uint16_t sequence = 0;
};
// The answer names the command it answers by its code, sequence and session, so that
// two tools commanding one board never take each other's answers. `owner` is the
// session whose motion the board runs or is starting (0: none, or one started without
// a session): a refused start (kRefusedNotIdle, kRefusedBusy) says who holds the board,
// and then `detail` is the code of the start that holds it (0: none).
struct CommandResult {
  CommandCode code = CommandCode::kStop;
  CommandOutcomeCode outcome = CommandOutcomeCode::kAccepted;
  std::uint8_t detail = 0;
  std::uint8_t sequence = 0;
  SessionId session = 0;
  SessionId owner = 0;
};
struct TrialConfig {
  Angle amplitude;
  std::uint16_t frequency_mHz = 500;
  std::uint8_t repetitions = 5;
  std::uint8_t rest_100ms = 15;
};
struct SweepConfig {
  Angle end_amplitude;
  std::uint16_t frequency_mHz = 500;
  std::uint8_t repetitions = 10;
  std::uint8_t rest_100ms = 5;
};
// A window (the loading and unloading half of a flexion or an extension) begins: sent
// by the main loop's first pass after the tick whose setpoint enters the window's
// loading segment, so a host can mark the moment on other instruments (mjc trial
// --sync-line). start_tick is the WindowTicks.start_tick of the summary that follows
// at the window's end (the tracker's start, aligned by the velocity estimator's delay,
// lands on the same tick), unless the main loop missed ticks.
// config16: the low 16 bits of the ConfigDigest of the motion the window belongs to
// (MotionConfig names it whole), so a window is never taken for another motion's.
struct WindowStart {
  Motion motion = Motion::kFlexion;
  std::uint32_t start_tick = 0;
  std::uint16_t config16 = 0;
};
// A motion started: the board's first frame of it, right after the accepted start's
// CommandResult. Which start (kStartTrial, kStartSweep, kStartStream), the session that
// started it and the digest of the configuration it runs (0 for a stream), taken when
// the start was accepted: what runs, whoever sent a configuration since.
struct MotionConfig {
  CommandCode start = CommandCode::kStartTrial;
  SessionId session = 0;
  ConfigDigest config = 0;
};
struct WindowHeader {
  Motion motion = Motion::kFlexion;
  std::uint16_t repetition = 0;
  bool eta_valid = false;
  Ratio eta_percent;
  // The window's attachment fit (WindowFit, WindowFitResidual): kOk or why not.
  InterfaceFitStatus fit_status = InterfaceFitStatus::kTooFewSamples;
};
struct WindowEnergy {
  WireEnergy loading;
  WireEnergy unloading;
};
struct WindowWork {
  WireEnergy positive;
  WireEnergy negative;
};
struct WindowPeaks {
  Power peak_power;
  Torque peak_torque;
};
// WindowTicks carries the peak and the end as 16-bit offsets from the start, so a
// window (half a cycle) must last at most 65,535 ticks: 77 mHz and up at 10 kHz. A trial
// or sweep with longer windows is refused (kRefusedInvalid) with this detail, which
// lies beyond the TrajectoryError numbers.
inline constexpr std::uint8_t kDetailWindowTooLong = 64;
struct WindowTicks {
  std::uint32_t start_tick = 0;
  std::uint16_t peak_offset = 0;  // ticks from start
  std::uint16_t end_offset = 0;   // ticks from start
};
// The attachment's fit over the window (interface_fit.h), after WindowTicks: the
// window's last two frames. Zero values unless status is kOk.
struct WindowFit {
  Stiffness stiffness;  // k_i
  Damping damping;      // b_i
};
// Whether the fit has values travels in the WindowHeader (fit_status).
struct WindowFitResidual {
  Torque offset;        // τ_0
  Torque residual_rms;  // √(mean (τ − fit)²)
};
struct ParamWrite {
  ParamId id = ParamId::kHeartbeatHz;
  std::int32_t value = 0;
};
struct ParamRead {
  ParamId id = ParamId::kHeartbeatHz;
};
struct ParamValue {
  ParamId id = ParamId::kHeartbeatHz;
  std::int32_t value = 0;
  ParamStatus status = ParamStatus::kOk;
};
struct TelemetryAngles {
  Angle motor;
  Angle joint;
};
// The angle telemetry of a board on a CAN FD link: kSamples consecutive TelemetryAngles
// samples (at telemetry_angles_hz, oldest first) in one 48-byte frame, in place of one
// classical frame each. `first_sample` numbers the first of them in the board's count
// of angle samples since its start (it wraps at 2^32: 50 days at 1 kHz), so batch k+1
// starts kSamples after batch k and a host sees a lost frame as a gap, never as a
// silent jump between neighbours.
//
// Why 5: eight boards at 1 kHz on 1/5 Mbit/s must leave room (mjc busload,
// worst-case stuffing, with the other telemetry, heartbeats and window summaries):
// 4 + 5 × 8 = 44 bytes fit the 48-byte FD length, and the bus carries 26.6 % (one
// sample a frame: 50.0 %). 4 samples need the same 48 bytes (32.1 %); 3 fit in 32
// bytes (32.7 %); 7 in 64 bytes would save 2.6 points more and make the host wait 2 ms
// longer. Latency: a sample waits at most 4 telemetry periods for its frame, 4 ms at
// 1 kHz, plus the frame's 138 µs.
struct TelemetryAngleBatch {
  static constexpr std::size_t kSamples = 5;
  std::uint32_t first_sample = 0;
  std::array<Angle, kSamples> motor{};
  std::array<Angle, kSamples> joint{};
};
struct TelemetryTorque {
  Torque torque;
  Angle cable_side;
};
struct TelemetryPower {
  Power power;
  AngularVelocity joint_velocity;
};
struct TelemetryEnergy {
  Energy energy;
};
struct TelemetryControl {
  Angle setpoint;
  Duty duty;
  Segment segment = Segment::kIdle;
  BoardState state = BoardState::kIdle;
};
struct Heartbeat {
  BoardState state = BoardState::kIdle;
  bool calibrated = false;
  bool bridge_enabled = false;
  Fault fault = Fault::kNone;
  std::uint32_t tick = 0;
};
// Who a board is, sent at start-up and then ten times a second: the image it runs, the
// build that made it, why it last started, and an identity of the physical board (from
// the chip's unique id; a simulated board draws one), so that two boards answering with
// one node id are told apart.
// Record pages the board found unreadable at start-up (an ECC double error that a
// power cut during a save leaves): BoardInfo.flash_unreadable's bits. The other page's
// record was used; the next save of that record erases the bad page.
namespace flash_unreadable {
inline constexpr std::uint8_t kIdentityA = 1u << 0, kIdentityB = 1u << 1,
                              kCalibrationA = 1u << 2, kCalibrationB = 1u << 3;
}
struct BoardInfo {
  std::uint32_t build = 0;  // the build's commit: the first 8 hex digits of its hash
  bool dirty = false;       // built from a tree with uncommitted changes
  ImageKind image = ImageKind::kApplication;
  ResetCause reset_cause = ResetCause::kUnknown;
  std::uint16_t instance = 0;         // the physical board (hash of its unique id)
  std::uint8_t flash_unreadable = 0;  // flash_unreadable:: bits
};
struct HostHeartbeat {
  std::uint8_t sequence = 0;
  SessionId session = 0;
};
// "Every board, stop now": an emergency stop (mjc estop, a button on a GPIO line),
// broadcast to node 0 on the bus's highest-priority identifier. Each board latches
// Fault::kEmergencyStop in its next tick, which disables its bridge, whatever it was
// doing; only a ClearFaults releases it. No board answers (eight answers would only
// delay each other); the Fault frame each sends is the confirmation. The key guards
// against another protocol's frame on identifier 0 (CANopen's NMT is 0x000 with two
// bytes); `session` names the sender, 0 = none.
inline constexpr std::uint32_t kStopAllKey = 0x504F5453u;  // "STOP"
struct StopAll {
  std::uint32_t key = kStopAllKey;
  SessionId session = 0;
};

// --- the bootloader's messages (firmware/bootloader/BOOTLOADER.md) -----------------

// Where the bootloader is. Stable numbers.
enum class BootState : std::uint8_t {
  kHoldWindow = 1,  // a valid image boots unless a BootHold arrives (200 ms)
  kReady = 2,       // staying, waiting for an update (a Begin)
  kReceiving = 3,   // an update is in progress: chunks, then a commit
  kCommitted = 4,   // the new image is in flash and checked: waiting for a boot
};
constexpr bool ValidEnumValue(BootState s) {
  return static_cast<std::uint8_t>(s) >= 1 && static_cast<std::uint8_t>(s) <= 4;
}

// Why the bootloader stays instead of booting. Stable numbers.
enum class StayReason : std::uint8_t {
  kNone = 0,          // not staying (the hold window)
  kNoValidImage = 1,  // the image check at reset failed (BootStatus.error: how)
  kRequested = 2,     // the application asked for it before its reset
  kHoldFrame = 3,     // a BootHold came within the hold window
  kBootLoop = 4,      // the image reset 3 times without confirming a healthy start
  kUpdate = 5,        // an update began: the previous image is no longer whole
  kNoClock = 6,       // the crystal did not start: no hand-over on a clock that is
                      // not the designed one (ChipInfo says which and why)
};
constexpr bool ValidEnumValue(StayReason r) { return static_cast<std::uint8_t>(r) <= 6; }

// Errors of the bootloader. Stable numbers, never renumbered; 1-9 are the image
// checks (mjc::boot::ImageCheck, the same numbers), 16-31 the update's, 32 and up the
// running application's answers to a BootHold.
enum class BootError : std::uint8_t {
  kNone = 0,
  kNoImage = 1,            // no header: erased, or no magic
  kBadHeader = 2,          // damaged: size, version, CRC, commit mark or reserved bits
  kWrongBoard = 3,         // built for another board type
  kWrongHardware = 4,      // this board's hardware revision is outside the image's range
  kBadLength = 5,          // 0, not a multiple of 8, or larger than the region holds
  kBadLoadAddress = 6,     // linked for another address than the application region's
  kBadVectors = 7,         // initial stack pointer or reset vector implausible
  kImageCrc = 8,           // the image in flash does not match the header's CRC
  kUnreadable = 9,         // the flash failed a read of the header or image (an ECC
                           // error a cut update left): no image, ready for an update
  kNotReceiving = 16,      // a chunk or commit without a Begin
  kUnexpectedOffset = 17,  // a chunk not at the next offset (BootResult.next_offset)
  kBadChunk = 18,          // empty, not a multiple of 8 bytes, or past the image's end
  kOutOfRegion = 19,       // an erase or program outside the application region
  kFlashError = 20,        // the flash reported an error
  kIncomplete = 21,        // a commit before every byte of the image arrived
  kTransfer = 22,          // the ISO-TP transfer failed (sequence, timeout, overflow)
  kBadRequest = 23,        // an unknown or malformed request
  kNothingToBoot = 24,     // a boot request without a valid image
  // The running application's answer to a BootHold (it does not enter the bootloader):
  kMotionRunning = 32,  // a trial, calibration sweep or stream runs: stop it first
};
constexpr bool ValidEnumValue(BootError e) {
  const auto v = static_cast<std::uint8_t>(e);
  return v <= 9 || (v >= 16 && v <= 24) || v == 32;
}

// What a BootResult answers. Stable numbers.
enum class BootRequest : std::uint8_t {
  kHold = 1,    // BootHold
  kBegin = 2,   // ISO-TP: the new image's header
  kChunk = 3,   // ISO-TP: image bytes at an offset
  kCommit = 4,  // BootCommand: check the image in flash, write its header
  kBoot = 5,    // BootCommand: reset and start the image
  kAbort = 6,   // BootCommand: drop an update in progress
};
constexpr bool ValidEnumValue(BootRequest r) {
  return static_cast<std::uint8_t>(r) >= 1 && static_cast<std::uint8_t>(r) <= 6;
}

// The bootloader's heartbeat, every 100 ms and at each change. Its build is in the
// BoardInfo it also sends (image = kBootloader). `tick_ms` is its own clock since its
// start: the host bounds its waits by it.
struct BootStatus {
  BootState state = BootState::kReady;
  StayReason reason = StayReason::kNone;
  BootError error = BootError::kNone;   // the last error
  std::uint16_t progress_permille = 0;  // of the image programmed (0..1000)
  std::uint32_t tick_ms = 0;
};
// What the system clock runs from. Stable numbers.
enum class ClockSource : std::uint8_t {
  kHsi16 = 0,   // the internal 16 MHz RC alone (nothing faster came up)
  kHsePll = 1,  // the crystal through the PLL, 170 MHz: as designed
  kHsiPll = 2,  // the internal RC through the PLL, 170 MHz: the crystal failed
  kOther = 3,
};
constexpr bool ValidEnumValue(ClockSource c) { return static_cast<std::uint8_t>(c) <= 3; }

// How the crystal's clock bring-up ended (the G474 driver's ClockResult numbers).
// Stable numbers.
enum class ClockFault : std::uint8_t {
  kNone = 0,
  kVoltage = 1,        // the regulator did not settle
  kFlashLatency = 2,   // the flash did not take its wait states
  kHseTimeout = 3,     // the crystal was not ready within its timeout (5 ms)
  kPllTimeout = 4,     // the PLL did not lock
  kSwitchTimeout = 5,  // the system clock did not switch to the PLL
};
constexpr bool ValidEnumValue(ClockFault f) { return static_cast<std::uint8_t>(f) <= 5; }

// The chip as the bootloader found it, with every BoardInfo: the option bytes (the raw
// FLASH_OPTR of the G474: nSWBOOT0 bit 26, nBOOT0 bit 27, DBANK bit 22; the factory
// value is 0xFFEFF8AA), the reset flags of its reset (RCC_CSR's top byte, bits 24..31
// as bits 0..7: bit 0 reserved (0), then OBL, PIN, BOR, SFT, IWDG, WWDG, LPWR), the clock
// it runs on and how the crystal's bring-up ended; hse_ready: the crystal runs now (it
// may have started after its timeout).
struct ChipInfo {
  std::uint32_t option_bytes = 0;
  std::uint8_t reset_flags = 0;
  bool hse_ready = false;
  ClockSource clock = ClockSource::kHsePll;
  ClockFault clock_fault = ClockFault::kNone;
};
// FLASH_OPTR's boot bits (RM0440 FLASH_OPTR; CMSIS stm32g474xx.h).
inline constexpr std::uint32_t kOptrNswboot0 = 1u << 26;  // 0: BOOT0 from nBOOT0
inline constexpr std::uint32_t kOptrNboot0 = 1u << 27;
inline constexpr std::uint32_t kOptrDbank = 1u << 22;
// True when the chip samples its BOOT0 pin (PB8) at every reset: nSWBOOT0 = 1, the
// factory setting. A floating or high pin then starts ST's ROM bootloader.
constexpr bool BootsFromPin(std::uint32_t optr) { return (optr & kOptrNswboot0) != 0; }

// "Stay in the bootloader": in the hold window after a reset it makes the bootloader
// stay; to a running application, it asks it to enter the bootloader. The key guards
// against a frame meant for something else.
inline constexpr std::uint32_t kBootHoldKey = 0x444C4F48u;  // "HOLD"
struct BootHold {
  std::uint32_t key = kBootHoldKey;
};
struct BootCommand {
  BootRequest request = BootRequest::kCommit;  // kCommit, kBoot or kAbort
  std::uint8_t sequence = 0;
};
struct BootResult {
  BootRequest request = BootRequest::kBegin;
  BootError error = BootError::kNone;
  std::uint8_t sequence = 0;      // the request's
  std::uint32_t next_offset = 0;  // the image offset the bootloader expects next
};

template <class M>
struct Message;

// kBroadcast: sent to node 0, which every node takes (the identifier carries no node);
// otherwise to or from one node 1..8. kFd: a CAN FD frame (bit-rate switching), never
// classical; otherwise a classical frame.
#define MJC_MESSAGE_AS(Type, function, length, sender, broadcast, fd, ...) \
  template <>                                                              \
  struct Message<Type> {                                                   \
    using T = Type;                                                        \
    static constexpr Function kFunction = Function::function;              \
    static constexpr const char* kName = #Type;                            \
    static constexpr std::uint8_t kLength = length;                        \
    static constexpr Sender kSender = Sender::sender;                      \
    static constexpr bool kBroadcast = broadcast;                          \
    static constexpr bool kFd = fd;                                        \
    static constexpr auto kSignals = std::make_tuple(__VA_ARGS__);         \
  }
#define MJC_MESSAGE_TO(Type, function, length, sender, broadcast, ...) \
  MJC_MESSAGE_AS(Type, function, length, sender, broadcast, false, __VA_ARGS__)
#define MJC_MESSAGE(Type, function, length, sender, ...) \
  MJC_MESSAGE_AS(Type, function, length, sender, false, false, __VA_ARGS__)

MJC_MESSAGE(FaultEvent, kFault, 7, kBoard, MakeSignal("fault_code", &T::fault, 0, 16),
            MakeSignal("tick", &T::tick, 16, 32, "tick"),
            MakeSignal("state", &T::state, 48, 8));
MJC_MESSAGE(Command, kCommand, 8, kHost, MakeSignal("command", &T::code, 0, 8),
            MakeSignal("sequence", &T::sequence, 8, 8),
            MakeSignal("session", &T::session, 16, 16),
            MakeSignal("config", &T::config, 32, 32));
MJC_MESSAGE(Setpoint, kSetpoint, 6, kHost,
            MakeSignal("position_rad", &T::position, 0, 32, "rad"),
            MakeSignal("sequence", &T::sequence, 32, 16));
MJC_MESSAGE(CommandResult, kCommandResult, 8, kBoard,
            MakeSignal("command", &T::code, 0, 8),
            MakeSignal("outcome", &T::outcome, 8, 8),
            MakeSignal("detail", &T::detail, 16, 8),
            MakeSignal("sequence", &T::sequence, 24, 8),
            MakeSignal("session", &T::session, 32, 16),
            MakeSignal("owner", &T::owner, 48, 16));
MJC_MESSAGE(TrialConfig, kTrialConfig, 8, kHost,
            MakeSignal("amplitude_rad", &T::amplitude, 0, 32, "rad"),
            MakeSignal("frequency_mHz", &T::frequency_mHz, 32, 16, "mHz"),
            MakeSignal("repetitions", &T::repetitions, 48, 8),
            MakeSignal("rest_100ms", &T::rest_100ms, 56, 8, "100 ms"));
MJC_MESSAGE(SweepConfig, kSweepConfig, 8, kHost,
            MakeSignal("end_amplitude_rad", &T::end_amplitude, 0, 32, "rad"),
            MakeSignal("frequency_mHz", &T::frequency_mHz, 32, 16, "mHz"),
            MakeSignal("repetitions", &T::repetitions, 48, 8),
            MakeSignal("rest_100ms", &T::rest_100ms, 56, 8, "100 ms"));
MJC_MESSAGE(WindowStart, kWindowStart, 7, kBoard, MakeSignal("motion", &T::motion, 0, 8),
            MakeSignal("start_tick", &T::start_tick, 8, 32, "tick"),
            MakeSignal("config16", &T::config16, 40, 16));
MJC_MESSAGE(MotionConfig, kMotionConfig, 7, kBoard, MakeSignal("start", &T::start, 0, 8),
            MakeSignal("session", &T::session, 8, 16),
            MakeSignal("config", &T::config, 24, 32));
MJC_MESSAGE(WindowHeader, kWindowHeader, 8, kBoard,
            MakeSignal("motion", &T::motion, 0, 8),
            MakeSignal("repetition", &T::repetition, 8, 16),
            MakeSignal("eta_valid", &T::eta_valid, 24, 1),
            MakeSignal("fit_status", &T::fit_status, 25, 7),
            MakeSignal("eta_pct", &T::eta_percent, 32, 32, "%"));
MJC_MESSAGE(WindowEnergy, kWindowEnergy, 8, kBoard,
            MakeSignal("loading_J", &T::loading, 0, 32, "J"),
            MakeSignal("unloading_J", &T::unloading, 32, 32, "J"));
MJC_MESSAGE(WindowWork, kWindowWork, 8, kBoard,
            MakeSignal("positive_work_J", &T::positive, 0, 32, "J"),
            MakeSignal("negative_work_J", &T::negative, 32, 32, "J"));
MJC_MESSAGE(WindowPeaks, kWindowPeaks, 8, kBoard,
            MakeSignal("peak_power_W", &T::peak_power, 0, 32, "W"),
            MakeSignal("peak_torque_Nm", &T::peak_torque, 32, 32, "N.m"));
MJC_MESSAGE(WindowTicks, kWindowTicks, 8, kBoard,
            MakeSignal("start_tick", &T::start_tick, 0, 32, "tick"),
            MakeSignal("peak_offset", &T::peak_offset, 32, 16, "tick"),
            MakeSignal("end_offset", &T::end_offset, 48, 16, "tick"));
MJC_MESSAGE(WindowFit, kWindowFit, 8, kBoard,
            MakeSignal("stiffness_Nm_rad", &T::stiffness, 0, 32, "N.m/rad"),
            MakeSignal("damping_Nms_rad", &T::damping, 32, 32, "N.m.s/rad"));
MJC_MESSAGE(WindowFitResidual, kWindowFitResidual, 8, kBoard,
            MakeSignal("offset_Nm", &T::offset, 0, 32, "N.m"),
            MakeSignal("residual_rms_Nm", &T::residual_rms, 32, 32, "N.m"));
MJC_MESSAGE(ParamWrite, kParamWrite, 6, kHost, MakeSignal("param", &T::id, 0, 16),
            MakeSignal("value", &T::value, 16, 32));
MJC_MESSAGE(ParamRead, kParamRead, 2, kHost, MakeSignal("param", &T::id, 0, 16));
MJC_MESSAGE(ParamValue, kParamValue, 7, kBoard, MakeSignal("param", &T::id, 0, 16),
            MakeSignal("value", &T::value, 16, 32),
            MakeSignal("status", &T::status, 48, 8));
MJC_MESSAGE(TelemetryAngles, kTelemetryAngles, 8, kBoard,
            MakeSignal("motor_angle_rad", &T::motor, 0, 32, "rad"),
            MakeSignal("joint_angle_rad", &T::joint, 32, 32, "rad"));
// 4 + 5 × 8 bytes; the last 4 of the 48 are zero (an FD frame's length is one of 12,
// 16, 20, 24, 32, 48, 64 above 8).
MJC_MESSAGE_AS(TelemetryAngleBatch, kTelemetryAngleBatch, 48, kBoard, false, true,
               MakeSignal("first_sample", &T::first_sample, 0, 32, "sample"),
               MakeSignal("motor_angle_0_rad", &T::motor, 0, 32, 32, "rad"),
               MakeSignal("joint_angle_0_rad", &T::joint, 0, 64, 32, "rad"),
               MakeSignal("motor_angle_1_rad", &T::motor, 1, 96, 32, "rad"),
               MakeSignal("joint_angle_1_rad", &T::joint, 1, 128, 32, "rad"),
               MakeSignal("motor_angle_2_rad", &T::motor, 2, 160, 32, "rad"),
               MakeSignal("joint_angle_2_rad", &T::joint, 2, 192, 32, "rad"),
               MakeSignal("motor_angle_3_rad", &T::motor, 3, 224, 32, "rad"),
               MakeSignal("joint_angle_3_rad", &T::joint, 3, 256, 32, "rad"),
               MakeSignal("motor_angle_4_rad", &T::motor, 4, 288, 32, "rad"),
               MakeSignal("joint_angle_4_rad", &T::joint, 4, 320, 32, "rad"));
static_assert(TelemetryAngleBatch::kSamples == 5, "the signal list names 5 samples");
MJC_MESSAGE(TelemetryTorque, kTelemetryTorque, 8, kBoard,
            MakeSignal("torque_Nm", &T::torque, 0, 32, "N.m"),
            MakeSignal("cable_angle_rad", &T::cable_side, 32, 32, "rad"));
MJC_MESSAGE(TelemetryPower, kTelemetryPower, 8, kBoard,
            MakeSignal("power_W", &T::power, 0, 32, "W"),
            MakeSignal("joint_velocity_rad_s", &T::joint_velocity, 32, 32, "rad/s"));
MJC_MESSAGE(TelemetryEnergy, kTelemetryEnergy, 8, kBoard,
            MakeSignal("energy_J", &T::energy, 0, 64, "J"));
MJC_MESSAGE(TelemetryControl, kTelemetryControl, 8, kBoard,
            MakeSignal("setpoint_rad", &T::setpoint, 0, 32, "rad"),
            MakeSignal("duty", &T::duty, 32, 16),
            MakeSignal("segment", &T::segment, 48, 8),
            MakeSignal("state", &T::state, 56, 8));
MJC_MESSAGE(Heartbeat, kHeartbeat, 8, kBoard, MakeSignal("state", &T::state, 0, 8),
            MakeSignal("calibrated", &T::calibrated, 8, 1),
            MakeSignal("bridge_enabled", &T::bridge_enabled, 9, 1),
            MakeSignal("fault_code", &T::fault, 16, 16),
            MakeSignal("tick", &T::tick, 32, 32, "tick"));
MJC_MESSAGE(BoardInfo, kBoardInfo, 8, kBoard, MakeSignal("build", &T::build, 0, 32),
            MakeSignal("dirty", &T::dirty, 32, 1), MakeSignal("image", &T::image, 33, 3),
            MakeSignal("reset_cause", &T::reset_cause, 36, 4),
            MakeSignal("instance", &T::instance, 40, 16),
            MakeSignal("flash_unreadable", &T::flash_unreadable, 56, 8));
MJC_MESSAGE(HostHeartbeat, kHostHeartbeat, 3, kHost,
            MakeSignal("sequence", &T::sequence, 0, 8),
            MakeSignal("session", &T::session, 8, 16));
MJC_MESSAGE_TO(StopAll, kStopAll, 6, kHost, true, MakeSignal("key", &T::key, 0, 32),
               MakeSignal("session", &T::session, 32, 16));
MJC_MESSAGE(BootStatus, kBootStatus, 8, kBoard, MakeSignal("state", &T::state, 0, 4),
            MakeSignal("reason", &T::reason, 4, 4), MakeSignal("error", &T::error, 8, 8),
            MakeSignal("progress_permille", &T::progress_permille, 16, 16, "1/1000"),
            MakeSignal("tick_ms", &T::tick_ms, 32, 32, "ms"));
MJC_MESSAGE(ChipInfo, kChipInfo, 7, kBoard,
            MakeSignal("option_bytes", &T::option_bytes, 0, 32),
            MakeSignal("reset_flags", &T::reset_flags, 32, 8),
            MakeSignal("hse_ready", &T::hse_ready, 40, 1),
            MakeSignal("clock", &T::clock, 44, 4),
            MakeSignal("clock_fault", &T::clock_fault, 48, 8));
MJC_MESSAGE(BootHold, kBootHold, 4, kHost, MakeSignal("key", &T::key, 0, 32));
MJC_MESSAGE(BootCommand, kBootCommand, 2, kHost, MakeSignal("request", &T::request, 0, 8),
            MakeSignal("sequence", &T::sequence, 8, 8));
MJC_MESSAGE(BootResult, kBootResult, 8, kBoard, MakeSignal("request", &T::request, 0, 8),
            MakeSignal("error", &T::error, 8, 8),
            MakeSignal("sequence", &T::sequence, 16, 8),
            MakeSignal("next_offset", &T::next_offset, 32, 32, "B"));

#undef MJC_MESSAGE
#undef MJC_MESSAGE_TO
#undef MJC_MESSAGE_AS

// Every message, for iteration (the DBC, bus load, decoding any frame).
using AllMessages =
    std::tuple<StopAll, FaultEvent, Command, Setpoint, CommandResult, TrialConfig,
               SweepConfig, WindowStart, WindowHeader, WindowEnergy, WindowWork,
               WindowPeaks, WindowTicks, WindowFit, WindowFitResidual, ParamWrite,
               ParamRead, ParamValue, TelemetryAngles, TelemetryAngleBatch,
               TelemetryTorque, TelemetryPower, TelemetryEnergy, TelemetryControl,
               Heartbeat, BoardInfo, HostHeartbeat, BootStatus, BootHold, BootCommand,
               BootResult, ChipInfo, MotionConfig>;

namespace detail {
template <class... M>
constexpr bool SentByBoardIn(std::uint8_t function, const std::tuple<M...>*) {
  return ((static_cast<std::uint8_t>(Message<M>::kFunction) == function &&
           Message<M>::kSender == Sender::kBoard) ||
          ...);
}
}  // namespace detail

// True for the function codes a board sends (its messages and its ISO-TP channel): a
// frame with one of these and a node's id is a sign of that board's life, where a
// host's frame to it (another tool's command or heartbeat) is not.
constexpr bool SentByBoard(std::uint8_t function) {
  return function == static_cast<std::uint8_t>(Function::kIsoTpFromBoard) ||
         function == static_cast<std::uint8_t>(Function::kBootIsoTpFromBoard) ||
         detail::SentByBoardIn(function, static_cast<const AllMessages*>(nullptr));
}
static_assert(SentByBoard(static_cast<std::uint8_t>(Function::kHeartbeat)) &&
              !SentByBoard(static_cast<std::uint8_t>(Function::kHostHeartbeat)));

}  // namespace mjc::protocol
