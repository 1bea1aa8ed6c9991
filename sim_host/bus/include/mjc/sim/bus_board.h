// The simulated joint board on a CAN bus of its own inside this process, driven by the
// host library as `mjc trial` and `mjc calibrate` drive a board: on one side the
// board (the firmware application and its CAN node on the plant, SimBoard), on the
// other any number of host links (a host::BoardClient's, an ISO-TP channel's).
//
// Lock-stepped, in one thread: the board runs only while a host link waits for a frame
// (a Receive with a timeout), one tick and one main-loop pass at a time, until a frame
// for that link arrives or the timeout has passed in the board's time. What the host
// sends reaches the board's controller at once and is taken by its next main-loop pass.
// So what the board is commanded, and at which of its ticks, depends on nothing but
// what it sent before: a run is the same bit for bit on any machine, at any load, and
// without threads to hand frames over (the paper's trials run many boards side by side
// instead). The host's clock is the board's (Clock()): every wait of BoardClient —
// its patience, the silence bound, its heartbeats' cadence — is counted in board time.
// A bus, its links and its client belong to one thread at a time.
//
// What the protocol does not carry at the full tick rate (the plant's ground truth,
// the board's per-tick values) stays on the board's side: SetBeforeTick and
// SetAfterTick let the simulator read it there (a probe; the host never sees it).
#pragma once

#include <array>
#include <chrono>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <vector>

#include "hal/can_port.h"
#include "mjc/host/board_client.h"
#include "mjc/host/can_link.h"
#include "mjc/sim/sim_board.h"

namespace mjc::sim {

class BusBoard {
 public:
  // The board with node id `node` on the plant of `params`, powered up at rest.
  BusBoard(const plant::PlantParams& params, const ControlConfig& config,
           std::uint8_t node = 1);
  ~BusBoard();
  BusBoard(const BusBoard&) = delete;
  BusBoard& operator=(const BusBoard&) = delete;

  // A new host link on the bus: it receives every frame the board sends from now on
  // (through its filters); what it sends goes to the board. Its Receive with a timeout
  // runs the board (see above); Receive(0) takes only what is there. The bus must
  // outlive it.
  std::unique_ptr<host::CanLink> Connect();

  // The host's client of this board, as the tools make theirs: on a link of its own,
  // sending the host's heartbeats (a motion it starts is supervised by them), on the
  // board's clock. Made on first use.
  host::BoardClient& client();

  // The board's time as a steady_clock time point (tick count × tick period): the
  // clock of the host's waits on this bus.
  host::BoardClient::Clock Clock() const;

  // Runs the board `ticks` ticks with nobody waiting (frames keep queueing for the
  // links).
  void Run(std::uint64_t ticks);

  // The board's side. Called before every tick (the board's frames of the last pass
  // are out; `SimBoard::plant()` is at the instant the tick samples) and after it
  // (`app().last()` is the tick's result), before the main loop's pass.
  using TickHook = std::function<void(SimBoard&)>;
  void SetBeforeTick(TickHook hook) { before_tick_ = std::move(hook); }
  void SetAfterTick(TickHook hook) { after_tick_ = std::move(hook); }

  SimBoard& board() { return *board_; }
  plant::Plant& plant() { return board_->plant(); }
  app::JointApp& app() { return board_->app(); }
  std::uint32_t tick_hz() const { return board_->tick_hz(); }
  std::uint8_t node() const { return node_; }
  // Ticks run on this bus (the ticks of Run and of the links' waits).
  std::uint64_t ticks() const { return ticks_; }
  // Frames the board's controller took from the host links, and the frames it sent
  // of one function code.
  std::uint32_t from_host() const { return from_host_; }
  std::uint32_t sent(protocol::Function function) const {
    return sent_[static_cast<std::size_t>(function) & 0x7F];
  }

 private:
  class Port;
  class Link;
  friend class Port;
  friend class Link;

  void Step();
  void FromBoard(const protocol::CanFrame& frame);
  void Disconnect(Link* link);

  std::uint8_t node_;
  std::unique_ptr<Port> port_;
  std::unique_ptr<SimBoard> board_;
  std::vector<Link*> links_;
  std::deque<protocol::CanFrame> to_board_;
  std::unique_ptr<host::CanLink> client_link_;
  std::unique_ptr<host::BoardClient> client_;
  TickHook before_tick_, after_tick_;
  std::uint64_t ticks_ = 0;
  std::uint32_t from_host_ = 0;
  std::array<std::uint32_t, 128> sent_{};
};

}  // namespace mjc::sim
