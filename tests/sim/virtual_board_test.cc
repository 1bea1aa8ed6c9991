// The virtual joint board: the image's own start-up, drivers and application
// (firmware/boards/g474_joint) against the STM32G474 register models, bound to the
// plant, on an in-process CAN bus, run as fast as the machine runs it (no wall time in
// any verdict: every wait follows the board's own clock).
//
//  - Booting, one simulated second: no rule of the manual broken (the models'
//    violations); SYSCLK at 170 MHz from the PLL in Range 1 boost with 4 flash wait
//    states (asked of the RCC, PWR and FLASH models); the tick's interrupt at 10 kHz;
//    FDCAN at 1 Mbit/s nominal and 5 Mbit/s data; the BoardInfo frame with this build's
//    commit, the power-on reset and the instance folded from the chip's unique ID. The
//    start is confirmed to the bootloader (the handoff block) after 2 s of ticks, not
//    before.
//  - A host's BootHold at rest is answered and the application leaves for its
//    bootloader as on the chip: the stay request in the handoff block, a software reset
//    (no bootloader precedes the virtual board: its application starts again).
//  - A calibration uploaded over ISO-TP is programmed into the FLASH model, survives a
//    power cut (read back over the bus after the reboot) and a restart of the program
//    (the flash file); a flash file of another size is refused and left as it was.
//  - The paper's calibration sweep over the bus, fitted on the host, within 0.05° of the
//    plant's slack; uploaded, restored by a board with a subject donned, and a trial
//    whose analysed windows match the plant's ground truth within the bounds the
//    simulated board's bus trial is held to (tests/sim/bus_trial_test.cc: 2 % of the
//    loading energy, η within 1 point).
#include "mjc/g474board/virtual_board.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <array>
#include <filesystem>
#include <fstream>
#include <functional>
#include <optional>
#include <stdexcept>
#include <vector>

#include "board.h"
#include "mjc/boot/handoff.h"
#include "mjc/build_id.h"
#include "mjc/host/board_client.h"
#include "mjc/host/calibration_io.h"
#include "mjc/host/units.h"
#include "mjc/plant/params.h"
#include "mjc/protocol/calibration_record.h"
#include "mjc/protocol/codec.h"
#include "virtual_board_rig.h"

namespace {

using namespace mjc;
using namespace mjc::protocol;

constexpr std::array<std::uint32_t, 3> kUniqueId = {0x0031002Au, 0x4D4B5012u,
                                                    0x20313739u};

// A calibration upload's wait for the board's answer, in the board's own time (ample for
// programming the record into its flash). The upload is host::UploadCalibration's on a
// link of the in-process bus, as the simulator's scenarios send one.
constexpr int kUploadPatienceMs = 10000;

g474board::VirtualBoardConfig Config(const plant::PlantParams& params) {
  g474board::VirtualBoardConfig config;
  config.plant = params;
  config.node = 1;
  config.unique_id = kUniqueId;
  config.speed = 0;      // as fast as the machine runs it: no wall time in any verdict
  config.log = nullptr;  // quiet; the violations are checked below
  return config;
}

std::string Violations(const g474board::VirtualBoard& board) {
  std::string s;
  for (const auto& v : board.violations()) s += v.source + ": " + v.what + "\n";
  return s;
}

// Every frame the host link holds now.
std::vector<CanFrame> Drain(host::CanLink& link) {
  std::vector<CanFrame> frames;
  while (const auto r = link.Receive(0)) frames.push_back(r->frame);
  return frames;
}

// The first frame from the board `node` on `link` that `take` accepts; nullopt once the
// board has run 10 s of its own time (its heartbeats' ticks) without one.
std::optional<CanFrame> AwaitFrame(host::CanLink& link, std::uint8_t node,
                                   const std::function<bool(const CanFrame&)>& take) {
  std::optional<std::uint32_t> first_tick;
  for (;;) {
    const auto r = link.Receive(100);
    if (!r) continue;
    Heartbeat beat;
    if (NodeOf(r->frame.id) == node && Decode(r->frame, &beat) == DecodeError::kOk) {
      if (!first_tick) first_tick = beat.tick;
      if (beat.tick - *first_tick > 10 * kBoardTickHz) return std::nullopt;
    }
    if (take(r->frame)) return r->frame;
  }
}

// Until the board's first heartbeat: it is on the bus (a frame sent before its CAN
// controller has started is lost, as on the chip).
void AwaitUp(host::BoardClient& client) {
  host::WaitEnd end{};
  std::string why;
  ASSERT_TRUE(client.Await([&] { return client.status().heard; }, {}, &end, &why)) << why;
}

// A file of this process in the test's temporary folder, removed when it goes.
struct TempFile {
  explicit TempFile(const std::string& name)
      : path(::testing::TempDir() + "virtual_board_" + std::to_string(::getpid()) + "_" +
             name) {
    std::filesystem::remove(path);
  }
  ~TempFile() { std::filesystem::remove(path); }
  const std::string path;
};

TEST(VirtualBoard, BootsAsOnTheChip) {
  auto bus = host::InProcessBus::Create();
  auto board_link = bus->Connect();
  auto host_link = bus->Connect();
  g474board::VirtualBoard board(Config(plant::LoadPlantParams("default")),
                                board_link.get());

  board.RunUntil(0.5);
  ASSERT_NE(board.firmware(), nullptr) << "the firmware did not build its board";
  const std::uint32_t tick_half = board.firmware()->app().last().telemetry.tick;
  board.RunUntil(1.0);
  const std::uint32_t tick_one = board.firmware()->app().last().telemetry.tick;
  EXPECT_TRUE(board.violations().empty()) << Violations(board);

  g474model::VirtualChip& chip = board.chip();
  EXPECT_EQ(chip.rcc().sysclk_hz(), 170e6);
  EXPECT_EQ(chip.rcc().hclk_hz(), 170e6);
  EXPECT_TRUE(chip.pwr().boost());
  EXPECT_EQ(chip.flash().latency(), 4u);
  // The tick: TIM1's update every 100 µs, and the firmware's tick counter advanced by
  // exactly that rate over the second half of the second.
  EXPECT_NEAR(chip.tim1().UpdatePeriodSeconds(), 100e-6, 1e-12);
  EXPECT_EQ(tick_one - tick_half, 5000u);
  EXPECT_EQ(chip.fdcan1().nominal_bitrate(), 1e6);
  EXPECT_EQ(chip.fdcan1().data_bitrate(), 5e6);

  // Who the board says it is.
  std::uint32_t folded = kUniqueId[0] ^ kUniqueId[1] ^ kUniqueId[2];
  const auto instance = static_cast<std::uint16_t>(folded ^ (folded >> 16));
  int infos = 0;
  for (const CanFrame& f : Drain(*host_link)) {
    BoardInfo info;
    if (FunctionOf(f.id) != static_cast<std::uint8_t>(Function::kBoardInfo)) continue;
    ASSERT_EQ(Decode(f, &info), DecodeError::kOk);
    ++infos;
    EXPECT_EQ(NodeOf(f.id), 1);
    EXPECT_EQ(info.build, build::kCommit);
    EXPECT_EQ(info.dirty, build::kDirty);
    EXPECT_EQ(info.image, ImageKind::kApplication);
    EXPECT_EQ(info.reset_cause, ResetCause::kPowerOn);
    EXPECT_EQ(info.instance, instance);
  }
  EXPECT_GE(infos, 1);
  board.Stop();
  EXPECT_TRUE(board.violations().empty()) << Violations(board);
  EXPECT_EQ(board.Summary().resets, 0);
}

// PB8 pulled up and the factory option bytes (nSWBOOT0 = 1): the chip boots its ROM
// bootloader, which has no FDCAN on the G47x. No firmware runs, nothing reaches the bus.
TEST(VirtualBoard, APulledUpBoot0PinWithFactoryOptionBytesIsSilent) {
  auto bus = host::InProcessBus::Create();
  auto board_link = bus->Connect();
  auto host_link = bus->Connect();
  g474board::VirtualBoardConfig config = Config(plant::LoadPlantParams("default"));
  config.boot0 = g474model::Boot0Pin::kPulledUp;
  g474board::VirtualBoard board(config, board_link.get());
  board.RunUntil(0.5);
  EXPECT_GE(board.now_s(), 0.5);
  EXPECT_EQ(board.chip().boot_source(), g474model::BootSource::kSystemMemory);
  EXPECT_EQ(board.firmware(), nullptr) << "the firmware ran";
  EXPECT_TRUE(Drain(*host_link).empty()) << "the board was heard";
  board.Stop();
}

// The watchdog as the bootloader leaves it to the application (g474_platform.h): running,
// 100 ms (LSI 32 kHz, /32, reload 99), written through its keys as RM0440 IWDG asks.
void StartTheBootloadersWatchdog(g474model::VirtualChip& chip) {
  constexpr std::uint32_t kIwdg = 0x40003000;
  chip.Write(kIwdg + 0x00, 0xCCCC, 4);  // start (and the LSI)
  chip.Write(kIwdg + 0x00, 0x5555, 4);  // PR/RLR writable
  chip.Write(kIwdg + 0x04, 3, 4);       // /32
  chip.Write(kIwdg + 0x08, 99, 4);
  chip.AdvanceTo(chip.now() + 1'000'000'000);  // 1 ms: PVU/RVU clear
  chip.Write(kIwdg + 0x00, 0xAAAA, 4);
}

// A crystal that never starts, or one that starts 50 ms after HSEON (tSU(HSE) is about
// 2 ms), with the bootloader's 100 ms watchdog running: the application gives up on the
// crystal after 5 ms, feeding the watchdog, runs the same 170 MHz from HSI16, and says
// why on the bus — Fault::kBoardStartup in its heartbeats, the bridge never enabled —
// instead of resetting through the watchdog with nothing said.
void ExpectAnswersWithAClockFault(g474model::Picoseconds hse_startup) {
  auto bus = host::InProcessBus::Create();
  auto board_link = bus->Connect();
  auto host_link = bus->Connect();
  g474board::VirtualBoard board(Config(plant::LoadPlantParams("default")),
                                board_link.get());
  board.chip().rcc().SetHseStartup(hse_startup);
  StartTheBootloadersWatchdog(board.chip());
  board.RunUntil(1.0);
  EXPECT_EQ(board.Summary().resets, 0) << "no watchdog reset";
  EXPECT_TRUE(board.violations().empty()) << Violations(board);
  EXPECT_EQ(board.chip().rcc().sysclk_hz(), 170e6);
  EXPECT_EQ(board.chip().fdcan1().nominal_bitrate(), 1e6);
  int faulted = 0;
  for (const CanFrame& f : Drain(*host_link)) {
    Heartbeat beat;
    if (NodeOf(f.id) != 1 || Decode(f, &beat) != DecodeError::kOk) continue;
    // The held fault is raised at the main loop's pass and latched by the next tick: a
    // heartbeat from before the first tick may still show none.
    if (beat.tick > 0) {
      EXPECT_EQ(beat.fault, Fault::kBoardStartup) << "tick " << beat.tick;
      ++faulted;
    }
    EXPECT_FALSE(beat.bridge_enabled);
  }
  EXPECT_GE(faulted, 5) << "heartbeats with the fault";
  board.Stop();
}

TEST(VirtualBoard, WithADeadCrystalAnswersOnCanWithAStartupFault) {
  ExpectAnswersWithAClockFault(g474model::kNever);
}

TEST(VirtualBoard, WithACrystalFiftyMillisecondsLateAnswersOnCanWithAStartupFault) {
  ExpectAnswersWithAClockFault(50'000'000'000);
}

TEST(VirtualBoard, ConfirmsAHealthyStartAfterTwoSeconds) {
  // Two unconfirmed starts of this image so far, as the bootloader counts them.
  constexpr std::uint32_t kImageCrc = 0x5EED1234u;
  boot::SetBootAttempts(board::Handoff(), kImageCrc, 2);
  g474board::VirtualBoard board(Config(plant::LoadPlantParams("default")), nullptr);

  board.RunUntil(1.9);
  EXPECT_EQ(boot::BootAttempts(board::Handoff(), kImageCrc), 2u);
  board.RunUntil(2.1);
  EXPECT_EQ(boot::BootAttempts(board::Handoff(), kImageCrc), 0u);
  EXPECT_EQ(board::Handoff().attempts_magic, boot::kAttemptsMagic);
  board.Stop();
  EXPECT_TRUE(board.violations().empty()) << Violations(board);
}

TEST(VirtualBoard, EntersItsBootloaderOnAHostsHold) {
  auto bus = host::InProcessBus::Create();
  auto board_link = bus->Connect();
  auto host_link = bus->Connect();
  g474board::VirtualBoard board(Config(plant::LoadPlantParams("default")),
                                board_link.get());
  board.Resume();
  host::BoardClient client(host_link.get(), 1);
  AwaitUp(client);

  // At rest, a BootHold is answered {hold, none}; then the board leaves its
  // application: the stay request in the handoff block, a software reset. With no
  // bootloader in front of it, the virtual board starts its application again.
  auto answer_link = bus->Connect();
  std::string why;
  ASSERT_TRUE(client.Send(BootHold{}, &why)) << why;
  BootResult result;
  ASSERT_TRUE(AwaitFrame(*answer_link, 1, [&](const CanFrame& f) {
    return NodeOf(f.id) == 1 && Decode(f, &result) == DecodeError::kOk;
  })) << "no BootResult";
  EXPECT_EQ(result.request, BootRequest::kHold);
  EXPECT_EQ(result.error, BootError::kNone);
  board.Halt();
  board.RunUntil(board.now_s() + 0.2);
  EXPECT_EQ(board.Summary().resets, 1);
  ASSERT_NE(board.firmware(), nullptr);
  EXPECT_EQ(board.firmware()->node().config().identity.reset_cause,
            ResetCause::kSoftware);
  EXPECT_TRUE(boot::TakeStayRequest(board::Handoff(), /*software_reset=*/true));
  board.Stop();
  EXPECT_TRUE(board.violations().empty()) << Violations(board);
}

TEST(VirtualBoard, KeepsAnUploadedCalibrationOverAPowerCutAndARestart) {
  const TempFile flash("power_cut.flash");
  auto bus = host::InProcessBus::Create();
  auto board_link = bus->Connect();
  auto host_link = bus->Connect();
  auto upload_link = bus->Connect();
  g474board::VirtualBoardConfig config = Config(plant::LoadPlantParams("default"));
  config.flash_path = flash.path;
  CalibrationRecord record;
  record.backlash.c_right = Angle::Quantize(host::DegToRad(1.1));
  record.backlash.c_left = Angle::Quantize(host::DegToRad(-0.9));
  record.sea_stiffness = Stiffness::Quantize(0.65);
  std::string why;
  {
    g474board::VirtualBoard board(config, board_link.get());
    board.Resume();
    host::BoardClient client(host_link.get(), 1);
    AwaitUp(client);
    const host::UploadOutcome sent =
        host::UploadCalibration(client, *upload_link, record, kUploadPatienceMs, &why);
    ASSERT_EQ(sent.status, host::UploadStatus::kAnswered) << why;
    EXPECT_EQ(sent.result, CalibrationResult::kAccepted);

    // The power fails and comes back: the firmware boots again from the flash model.
    board.Halt();
    board.Post([&board] { board.chip().PowerCut(); });
    board.RunUntil(board.now_s() + 0.3);
    EXPECT_EQ(board.Summary().resets, 1);
    EXPECT_TRUE(board::LastBoot().calibration_restored);
    EXPECT_EQ(board::LastBoot().calibration_sequence, 1u);
    // Read back over the bus (a client of its own: its waits count the board's ticks,
    // which started again).
    auto after_link = bus->Connect();
    host::BoardClient after(after_link.get(), 1);
    board.Resume();
    AwaitUp(after);
    const auto back = host::ReadCalibration(after, &why);
    ASSERT_TRUE(back.has_value()) << why;
    EXPECT_TRUE(back->calibrated);
    EXPECT_EQ(back->record.backlash.c_right, record.backlash.c_right);
    EXPECT_EQ(back->record.backlash.c_left, record.backlash.c_left);
    EXPECT_EQ(back->record.sea_stiffness, record.sea_stiffness);
    board.Stop();
    EXPECT_EQ(board.Summary().resets, 1);
    EXPECT_TRUE(board.violations().empty()) << Violations(board);
  }
  // The program again, from the flash file.
  {
    g474board::VirtualBoard board(config, board_link.get());
    board.RunUntil(0.1);
    EXPECT_TRUE(board::LastBoot().calibration_restored);
    EXPECT_EQ(board::LastBoot().calibration_sequence, 1u);
  }
  // A file that is not a G474 flash (here two pages, as mjc sim's once was) is refused
  // before anything is written to it.
  const TempFile other("two_pages.flash");
  std::ofstream(other.path, std::ios::binary) << std::string(4096, '\x5A');
  config.flash_path = other.path;
  EXPECT_THROW(g474board::VirtualBoard(config, nullptr), std::runtime_error);
  EXPECT_EQ(std::filesystem::file_size(other.path), 4096u);
}

TEST(VirtualBoard, SurvivesAPowerCutDuringACalibrationSave) {
  // A second calibration's save is cut in its erase of page B: that page's double
  // words read back with ECC double errors (the FLASH model's NMI). The image's NMI
  // handler takes them, the store uses page A's record, and the board says which page
  // it could not read — instead of resetting on the NMI at every start.
  auto bus = host::InProcessBus::Create();
  auto board_link = bus->Connect();
  auto host_link = bus->Connect();
  auto upload_link = bus->Connect();
  g474board::VirtualBoard board(Config(plant::LoadPlantParams("default")),
                                board_link.get());
  board.Resume();
  host::BoardClient client(host_link.get(), 1);
  AwaitUp(client);
  CalibrationRecord record;
  record.backlash.c_right = Angle::Quantize(host::DegToRad(1.1));
  record.backlash.c_left = Angle::Quantize(host::DegToRad(-0.9));
  record.sea_stiffness = Stiffness::Quantize(0.65);
  std::string why;
  const host::UploadOutcome first =
      host::UploadCalibration(client, *upload_link, record, kUploadPatienceMs, &why);
  ASSERT_EQ(first.status, host::UploadStatus::kAnswered) << why;
  ASSERT_EQ(first.result, CalibrationResult::kAccepted);

  board.Halt();
  board.Post([&board] { board.chip().flash().CutPowerAfter(0, 11); });
  board.Resume();
  record.sea_stiffness = Stiffness::Quantize(0.7);
  (void)host::UploadCalibration(client, *upload_link, record, 2000, &why);
  board.Halt();
  ASSERT_EQ(board.Summary().resets, 1) << "the cut";
  const double cut_at = board.now_s();
  board.RunUntil(cut_at + 1.0);
  EXPECT_EQ(board.Summary().resets, 1) << "no reset after the cut's";
  EXPECT_TRUE(board::LastBoot().calibration_restored);
  EXPECT_EQ(board::LastBoot().calibration_sequence, 1u);
  EXPECT_GT(board.chip().nmis(), 0) << "the cut page was read";
  int infos = 0;
  for (const CanFrame& f : Drain(*host_link)) {
    BoardInfo info;
    if (FunctionOf(f.id) != static_cast<std::uint8_t>(Function::kBoardInfo)) continue;
    ASSERT_EQ(Decode(f, &info), DecodeError::kOk);
    if (info.flash_unreadable == 0) continue;  // the start before the cut
    ++infos;
    EXPECT_EQ(info.flash_unreadable, flash_unreadable::kCalibrationB);
  }
  EXPECT_GE(infos, 1);
  board.Stop();
  // The cut itself is the only thing the chip logged.
  for (const auto& v : board.violations()) {
    EXPECT_NE(v.what.find("power cut"), std::string::npos) << v.source << ": " << v.what;
  }
}

TEST(VirtualBoard, CalibratesAndRunsATrialAgainstPlantTruth) {
  const TempFile flash("trial.flash");
  auto bus = host::InProcessBus::Create();
  auto board_link = bus->Connect();
  auto host_link = bus->Connect();
  auto upload_link = bus->Connect();
  const plant::PlantParams robot = plant::LoadPlantParams("default");
  g474board::VirtualBoardConfig config = Config(robot);
  config.flash_path = flash.path;

  // The paper's sweep on the robot alone.
  {
    g474board::VirtualBoard board(config, board_link.get());
    board.Resume();
    host::BoardClient client(host_link.get(), 1);
    AwaitUp(client);
    const g474board::rig::CalibrationRun cal =
        g474board::rig::SweepAndFit(client, g474board::rig::PaperSweep(), robot);
    ASSERT_TRUE(cal.error.empty()) << cal.error;
    EXPECT_LT(cal.worst_error_deg(), 0.05);
    std::string why;
    const host::UploadOutcome sent = host::UploadCalibration(
        client, *upload_link, cal.record, kUploadPatienceMs, &why);
    ASSERT_EQ(sent.status, host::UploadStatus::kAnswered) << why;
    EXPECT_EQ(sent.result, CalibrationResult::kAccepted);
    board.Stop();
    EXPECT_TRUE(board.violations().empty()) << Violations(board);
  }

  // Subject 1's hand donned; the board restores the calibration from its flash. A bus
  // of its own: nothing the first board sent is heard.
  config.plant.interface = plant::LoadPlantParams("subject1").interface;
  auto trial_bus = host::InProcessBus::Create();
  auto trial_board_link = trial_bus->Connect();
  auto trial_host_link = trial_bus->Connect();
  g474board::VirtualBoard board(config, trial_board_link.get());
  const g474board::rig::EnergyTruth truth(board);
  board.Resume();
  host::BoardClient client(trial_host_link.get(), 1);
  AwaitUp(client);
  const g474board::rig::TrialRun run =
      g474board::rig::RunTrialAgainstTruth(client, truth, g474board::rig::JudgedTrial());
  board.Stop();
  ASSERT_TRUE(run.error.empty()) << run.error;
  EXPECT_TRUE(board::LastBoot().calibration_restored);
  for (const g474board::rig::WindowError& w : run.flexions) {
    EXPECT_NEAR(w.loading_J, w.truth_loading_J, 0.02 * w.truth_loading_J);
    EXPECT_NEAR(w.unloading_J, w.truth_unloading_J, 0.02 * w.truth_loading_J);
    EXPECT_NEAR(w.eta_pct, w.truth_eta_pct, 1.0);
  }
  EXPECT_TRUE(board.violations().empty()) << Violations(board);
  EXPECT_EQ(board.Summary().resets, 0);
}

}  // namespace
