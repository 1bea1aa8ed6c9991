// The board's CAN side, a transport: received frames (and calibration records over
// ISO-TP) are decoded into the joint service's requests (mjc/service/joint_service.h),
// its reports and the tick's telemetry are encoded as frames (angle samples batched on
// a CAN FD link) on a transmit queue the CAN driver drains. What the board decides
// (verdicts, supervision, the calibration's store, the window fits) is the service's.
//
// Contexts: HandleFrame and Poll run in the main loop (never in the control tick);
// the driver's transmit path pops frames from the queue (SPSC, so it may be an
// interrupt). Nothing here allocates or blocks.
//
// Every received frame is accounted for: handled, ignored (another node's or a
// board-to-host message), or malformed (counted by DecodeError and dropped).
#pragma once

#include <array>
#include <cstdint>

#include "mjc/app/board_clock.h"
#include "mjc/app/calibration_store.h"
#include "mjc/app/joint_app.h"
#include "mjc/app/spsc_queue.h"
#include "mjc/protocol/calibration_record.h"
#include "mjc/protocol/codec.h"
#include "mjc/protocol/isotp.h"
#include "mjc/service/joint_service.h"

namespace mjc::app {

struct CanNodeConfig {
  std::uint8_t node = 1;  // 1..8
  protocol::TelemetryRates rates;
  // Streamed setpoints older than this stop the motor (command timeout, latched),
  // [1, 100] ms as a parameter (protocol/params.h). The default stops a motor whose host
  // went quiet within 50.2 ms (the timeout, the main loop's poll, the next tick), under
  // the 100 ms goal for lost commands, while a host streaming at 100 Hz may miss four
  // setpoints.
  std::uint16_t stream_timeout_ms = 50;
  // Host supervision: a motion (calibration sweep, trial, stream) started with a
  // session id is stopped (kHostHeartbeatLost, latched) when that session's heartbeat
  // stays away this long; other sessions' heartbeats do not count, so another tool
  // cannot keep alive a motion whose commander died. A motion started without a
  // session (0: a tool that sends no heartbeats) is not supervised. As a parameter
  // [200, 1000] ms (protocol/params.h); 0 (off) only compiled into a test's board. The
  // default tolerates two lost heartbeats at the host's 10 Hz.
  std::uint16_t host_timeout_ms = 300;
  // The joint's rated SEA torque (joint_torque_limit): the control configuration's
  // torque_max never exceeds it. The image's ceiling from a reset; a tool that knows
  // the joint's description (mjc calibrate --robot, mjc trial --robot) sends the
  // description's, and from then on it can only be tightened until the next reset.
  Torque joint_torque_limit = protocol::kTorqueCeiling;
  // Largest setpoint speed while streaming, rad/s.
  AngularVelocity stream_rate = AngularVelocity::FromDouble(2.0);
  // The board's link carries CAN FD (the G474's FDCAN runs FD with bit-rate switching):
  // the angle telemetry then goes as TelemetryAngleBatch, kSamples samples a 48-byte
  // frame, which eight boards at 1 kHz fit in with room to spare; on a classical link
  // (false) one TelemetryAngles frame a sample, as classical CAN carries.
  bool fd = false;
  // Who the board is (BoardInfo): sent at the first poll and then at rates.info_hz. The
  // board fills in its build, its reset cause and its instance.
  protocol::BoardInfo identity;
  // The board has a bootloader to enter on a host's BootHold (JointBoard sets it when it
  // is given a hal::BootEntry). Without one a BootHold is ignored, as on a board whose
  // filters do not take it.
  bool bootloader = false;
};

struct CanNodeCounters {
  // Every received frame lands in exactly one of these four.
  std::uint32_t handled = 0;
  std::uint32_t ignored = 0;  // another node's, or a board-to-host message
  std::array<std::uint32_t, protocol::kDecodeErrorCount> malformed{};  // by DecodeError
  std::uint32_t isotp_malformed = 0;  // on the ISO-TP channel, no valid PCI
  // Lost on the way out: the transmit queue or the tick's event queue was full.
  std::uint32_t tx_dropped = 0;
  std::uint32_t events_dropped = 0;
  std::uint32_t stream_timeouts = 0;
  std::uint32_t host_timeouts = 0;
  std::uint32_t bus_off = 0;  // bus-off events the driver reported (each one stops us)
  std::uint32_t boot_holds_refused = 0;  // BootHolds answered kMotionRunning
  std::uint32_t emergency_stops = 0;     // StopAll frames taken (each one stops us)
  std::uint32_t isotp_errors = 0;  // transfers dropped (sequence, timeout, overflow)
  std::uint32_t calibrations_accepted = 0;
  std::uint32_t calibrations_refused = 0;
  std::uint32_t storage_failures = 0;

  std::uint32_t received() const {
    std::uint32_t n = handled + ignored + isotp_malformed;
    for (const std::uint32_t m : malformed) n += m;
    return n;
  }
};

class CanNode final : public service::ReportSink {
 public:
  // The board's node: the service (which must outlive the node) takes its requests and
  // sends it its reports; the service's owner polls it before the node (JointBoard).
  CanNode(service::JointService* service, const CanNodeConfig& config);
  CanNode(const CanNode&) = delete;
  CanNode& operator=(const CanNode&) = delete;

  // A frame from the bus: this node's, or a broadcast StopAll (every node's: the next
  // tick latches Fault::kEmergencyStop and disables the bridge).
  void HandleFrame(const protocol::CanFrame& frame);

  // Once per control tick (after it and the service's poll), in the main loop: an
  // upload that timed out, telemetry at its rates, the heartbeat, BoardInfo.
  void Poll();

  // The driver's side of the transmit queue.
  bool PopTx(protocol::CanFrame* out) { return tx_.Pop(out); }

  // The driver saw its controller go bus-off (main loop context). The board can no
  // longer hear a stop, so the motor stops (kCanBusOff, latched) and the event is
  // counted; the driver restarts the controller (bus-off recovery: 128 × 11 recessive
  // bits) and the queued frames go out once it is back. Clearing the fault needs a
  // ClearFaults from the host, which proves the bus works again.
  void OnBusOff();

  // A host's BootHold was accepted (the board rests, nothing waits to be applied and
  // saved, the answer is queued): the board should now enter its bootloader
  // (hal::BootEntry), once the queued frames have gone to the port. From the hold on,
  // starts and calibrations are refused as busy.
  bool EnterBootloaderNow() const { return service_->EnterBootloaderNow(); }

  CanNodeCounters counters() const;
  const CanNodeConfig& config() const { return config_; }
  // Record pages found unreadable at start-up (protocol::flash_unreadable bits), told
  // in every BoardInfo from now on.
  void AddFlashUnreadable(std::uint8_t bits) {
    config_.identity.flash_unreadable =
        static_cast<std::uint8_t>(config_.identity.flash_unreadable | bits);
  }

 private:
  template <class M>
  void Send(const M& message) {
    Push(protocol::Encode(message, config_.node));
  }
  void Push(const protocol::CanFrame& frame);
  std::uint32_t tick_hz() const { return service_->tick_hz(); }
  // The node's settings that are the service's: told again after every write of them.
  void TellSupervision();

  // A service's report, as frames (can_node_reports.cc).
  void DoTake(const service::Report& report) override;
  // Parameters (can_node_params.cc).
  void HandleParam(protocol::ParamId id, bool write, std::int32_t value);
  void SendParam(protocol::ParamId id, protocol::ParamStatus status);
  // A refused write's answer: the status and the bound it names.
  void RefuseParam(protocol::ParamId id, protocol::ParamStatus status,
                   std::int32_t bound);
  // Calibration records over ISO-TP (can_node_upload.cc).
  void HandleIsoTp(const protocol::CanFrame& frame);
  void PollUpload();
  void ReplyCalibration(protocol::CalibrationResult result, std::uint8_t detail);
  // Reports and telemetry as frames (can_node_reports.cc).
  void SendWindow(const WindowSummary& w, const InterfaceFit& fit);
  void SendTelemetry(const JointApp::Snapshot& last);
  // One angle sample: a frame of its own, or (FD) into the batch, sent once full.
  void SendAngles(const Telemetry& t);

  service::JointService* service_;
  CanNodeConfig config_;
  CanNodeCounters counters_;
  // 64 frames: a pass of the main loop queues at most a window (7 frames), the
  // telemetry due (7), a reply to each frame it took (JointBoard::kMostFramesPerPoll)
  // and a started motion's MotionConfig.
  SpscQueue<protocol::CanFrame, 64> tx_;
  protocol::IsoTpReceiver isotp_;
  Cadence angles_, torque_, power_, energy_, control_, heartbeat_, info_;
  // FD: the batch being filled and how many samples it holds; first_sample counts every
  // angle sample the board has taken since its start.
  protocol::TelemetryAngleBatch batch_;
  std::size_t batch_fill_ = 0;
};

}  // namespace mjc::app
