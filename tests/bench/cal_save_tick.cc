// The control tick's worst duration while the board saves its calibration, for ./bench
// (tick_worst_cycles_during_cal_save): the virtual board (the joint image's code on the
// G474 register models, sim_host/g474_board) takes a calibration upload over an
// in-process bus and programs it into its calibration pages in bank 2 — a page erase
// (22 ms of the FLASH model's busy time) and nine double words — while its 10 kHz tick
// keeps running. Every tick whose plant step falls while the FLASH model is busy, and
// the one after, is sampled (board::LastTickCycles, the image's own DWT measurement).
//
// What the figure captures: the tick's register accesses at their cost, its
// interrupt entry and exit, the work the firmware declares (SpendCycles), preemption of
// the flash driver's busy-wait, and any bus stall the FLASH model imposes (a read of
// the bank being erased stalls; the tick reads none). What it cannot capture: the virtual
// chip executes no instructions, so instruction fetches, the flash's wait states and the
// ART instruction cache being on or off (the reason the driver keeps ICEN on during an
// erase, as ST's HAL does) leave no trace in it. Those need the board (DWT on silicon).
#include <algorithm>
#include <cstdio>
#include <string>

#include "board.h"
#include "mjc/g474board/virtual_board.h"
#include "mjc/host/board_client.h"
#include "mjc/host/calibration_io.h"
#include "mjc/host/units.h"
#include "mjc/plant/params.h"

int main() {
  using namespace mjc;
  auto bus = host::InProcessBus::Create();
  auto board_link = bus->Connect();
  auto host_link = bus->Connect();
  auto upload_link = bus->Connect();
  g474board::VirtualBoardConfig config;
  config.plant = plant::LoadPlantParams("default");
  config.node = 1;
  config.speed = 0;  // as fast as the machine runs it: the figure is in board cycles
  config.log = nullptr;
  g474board::VirtualBoard board(config, board_link.get());
  std::uint32_t worst = 0, worst_outside = 0;
  long sampled = 0;
  bool was_busy = false;
  board.SetStepObserver([&](const plant::Plant&, std::uint32_t) {
    const bool busy = board.chip().flash().busy();
    const std::uint32_t cycles = board::LastTickCycles();
    if (busy || was_busy) {
      worst = std::max(worst, cycles);
      ++sampled;
    } else {
      worst_outside = std::max(worst_outside, cycles);
    }
    was_busy = busy;
  });
  board.Resume();
  host::BoardClient client(host_link.get(), 1);
  host::WaitEnd end{};
  std::string why;
  if (!client.Await([&] { return client.status().heard; }, {}, &end, &why)) {
    std::fprintf(stderr, "cal_save_tick: the board did not come up: %s\n", why.c_str());
    return 1;
  }
  protocol::CalibrationRecord record;
  record.backlash.c_right = Angle::Quantize(host::DegToRad(1.1));
  record.backlash.c_left = Angle::Quantize(host::DegToRad(-0.9));
  record.sea_stiffness = Stiffness::Quantize(0.65);
  const host::UploadOutcome sent =
      host::UploadCalibration(client, *upload_link, record, 10000, &why);
  board.Stop();
  if (sent.status != host::UploadStatus::kAnswered ||
      sent.result != protocol::CalibrationResult::kAccepted || sampled == 0) {
    std::fprintf(stderr, "cal_save_tick: the calibration was not saved (%s)\n",
                 why.c_str());
    return 1;
  }
  std::printf(
      "tick_worst_cycles_during_cal_save: %u cycles (virtual board, %ld ticks during "
      "the save's erase and programs; %u outside it; budget 17,000; instruction fetch "
      "and caches not modelled)\n",
      worst, sampled, worst_outside);
  return 0;
}
