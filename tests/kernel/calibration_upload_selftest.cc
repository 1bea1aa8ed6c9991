// Calibration upload over real ISO-TP: inside the VM, a board (the firmware's JointBoard
// on a raw SocketCAN socket, ticking at 10 kHz) receives a calibration record sent by the
// Linux kernel's own ISO-TP implementation (the host's IsoTpLink) — an ISO-TP stack we
// did not write — and answers [result, detail]. A corrupted record is refused with its
// reason and the old calibration stays. Prints "cal_upload_ms: N ms" (end to end: send,
// board applies, reply received) and "N passed, N failed".
#include <atomic>
#include <chrono>
#include <cstdio>
#include <string>
#include <thread>

#include "mjc/app/joint_board.h"
#include "mjc/host/can_link.h"
#include "mjc/protocol/calibration_record.h"
#include "mjc/sim/link_can_port.h"
#include "self_check.h"

namespace {

using namespace mjc;
using namespace mjc::protocol;

kernel_test::SelfCheck check;

struct QuietIo {
  Sample ISR_Read() {
    Sample s;
    s.joint_frame = EncodeJointFrame(0, false);
    return s;
  }
  void ISR_Write(const Actuation&) {}
};

}  // namespace

int main() {
  std::string why;
  auto board_link = host::SocketCanLink::Open("vcan0", &why);
  if (!board_link) {
    std::printf("FAIL open vcan0: %s\n0 passed, 1 failed\n", why.c_str());
    return 1;
  }
  sim::LinkCanPort port(board_link.get());
  static app::JointBoard joint_board(app::JointBoardConfig{}, &port, nullptr);  // node 1
  const app::JointApp& app = joint_board.app();
  const app::CanNode& node = joint_board.node();
  std::atomic<bool> stop{false};
  std::thread board([&] {
    QuietIo io;
    auto next = std::chrono::steady_clock::now();
    while (!stop) {
      joint_board.ISR_Tick(io);
      joint_board.Poll();
      next += std::chrono::microseconds(100);
      std::this_thread::sleep_until(next);
    }
  });

  const std::uint32_t to_board =
      MakeId(static_cast<std::uint8_t>(Function::kIsoTpToBoard), 1);
  const std::uint32_t from_board =
      MakeId(static_cast<std::uint8_t>(Function::kIsoTpFromBoard), 1);
  auto host = host::IsoTpLink::Open("vcan0", to_board, from_board, &why);
  check(host != nullptr, "host ISO-TP socket: " + why);
  if (host) {
    CalibrationRecord record;
    record.backlash.c_right = Angle::FromDouble(0.0195);
    record.backlash.c_left = Angle::FromDouble(-0.0161);
    record.sea_stiffness = Stiffness::FromDouble(0.64);
    record.joint_zero_count = 123;
    const auto bytes = EncodeCalibration(record);

    // The answers are waited for without a deadline that a slow machine could miss:
    // the cap only ends a wait for an answer that will not come. The board answers an
    // accepted record once its tick has applied it.
    constexpr int kCapMs = 300000;
    const auto t0 = std::chrono::steady_clock::now();
    check(host->Send(bytes, &why), "upload 48-byte record: " + why);
    auto reply = host->Receive(kCapMs, &why);
    const double ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0)
            .count();
    check(reply && reply->size() == 2 && (*reply)[0] == 0 && (*reply)[1] == 0,
          "board answers [accepted, 0]" + (reply ? std::string() : ": " + why));
    std::printf("cal_upload_ms: %.1f ms\n", ms);

    auto bad = bytes;
    bad[10] ^= 0x40;  // c_r corrupted in transit
    host->Send(bad, &why);
    reply = host->Receive(kCapMs, &why);
    check(reply && reply->size() == 2 &&
              (*reply)[0] == static_cast<std::uint8_t>(CalibrationResult::kBadCrc),
          "corrupted record refused with kBadCrc");
  }
  stop = true;
  board.join();
  // Read once the board's thread has stopped: what it applied, and kept.
  const ControlConfig& c = app.control().config();
  check(app.calibrated() && c.backlash.c_right == Angle::FromDouble(0.0195) &&
            c.backlash.c_left == Angle::FromDouble(-0.0161) &&
            c.sea_stiffness == Stiffness::FromDouble(0.64) &&
            c.joint_encoder.zero_offset == 123,
        "board applied c_r, c_l, stiffness and zero count, and kept them");
  check(node.counters().calibrations_accepted == 1 &&
            node.counters().calibrations_refused == 1,
        "board counters: 1 accepted, 1 refused");
  return check.Finish();
}
