#include "mjc/sim/bus_board.h"

#include <algorithm>

namespace mjc::sim {

// The board's CAN controller: what it sends goes to every host link at once (a bus
// that never loses or reorders a frame); it takes the host's frames in the order sent.
class BusBoard::Port final : public hal::CanPort {
 public:
  explicit Port(BusBoard* bus) : bus_(bus) {}

 private:
  bool DoSend(const protocol::CanFrame& frame) override {
    ++sent_;
    bus_->FromBoard(frame);
    return true;
  }
  bool DoReceive(protocol::CanFrame* frame) override {
    if (bus_->to_board_.empty()) return false;
    *frame = bus_->to_board_.front();
    bus_->to_board_.pop_front();
    ++bus_->from_host_;
    ++received_;
    return true;
  }
  std::uint32_t DoTakeBusOff() override { return 0; }
  hal::CanPortCounters DoCounters() const override {
    hal::CanPortCounters c;
    c.received = received_;
    c.sent = sent_;
    return c;
  }

  BusBoard* bus_;
  std::uint32_t received_ = 0, sent_ = 0;
};

// A host's end of the bus. Receive with a timeout runs the board until a frame for
// this link is there, or the timeout has passed in the board's time.
class BusBoard::Link final : public host::CanLink {
 public:
  explicit Link(BusBoard* bus) : bus_(bus) {}
  ~Link() override { bus_->Disconnect(this); }

  bool Passes(const protocol::CanFrame& f) const {
    return filters_.empty() ||
           std::any_of(filters_.begin(), filters_.end(), [&](const host::IdFilter& x) {
             return (f.id & x.mask) == (x.id & x.mask);
           });
  }
  void Deliver(const protocol::CanFrame& frame) {
    host::ReceivedFrame r;
    r.frame = frame;
    // The board's time, not this machine's: a recording is then the same every run.
    r.timestamp_us =
        static_cast<std::int64_t>(bus_->ticks_ * 1'000'000u / bus_->board_->tick_hz());
    r.timestamp_s = static_cast<double>(r.timestamp_us) * 1e-6;
    queue_.push_back(r);
  }

 private:
  bool DoSend(const protocol::CanFrame& frame, std::string*) override {
    bus_->to_board_.push_back(frame);
    ++stats_.sent;
    return true;
  }
  host::ReceiveResult DoReceive(int timeout_ms, std::string*) override {
    const std::uint64_t until =
        bus_->ticks_ + static_cast<std::uint64_t>(std::max(timeout_ms, 0)) *
                           bus_->board_->tick_hz() / 1000u;
    while (queue_.empty() && bus_->ticks_ < until) bus_->Step();
    if (queue_.empty()) return {host::ReceiveStatus::kTimeout, {}};
    host::ReceiveResult out{host::ReceiveStatus::kFrame, queue_.front()};
    queue_.pop_front();
    ++stats_.received;
    return out;
  }
  bool DoSetFilters(std::span<const host::IdFilter> filters, std::string*) override {
    filters_.assign(filters.begin(), filters.end());
    return true;
  }

  BusBoard* bus_;
  std::deque<host::ReceivedFrame> queue_;
  std::vector<host::IdFilter> filters_;
};

BusBoard::BusBoard(const plant::PlantParams& params, const ControlConfig& config,
                   std::uint8_t node)
    : node_(node), port_(std::make_unique<Port>(this)) {
  app::JointBoardConfig board_config{config, {}, 0, 1};
  board_config.can.node = node;
  board_ = std::make_unique<SimBoard>(params, board_config, port_.get());
}

BusBoard::~BusBoard() {
  client_.reset();
  client_link_.reset();
}

std::unique_ptr<host::CanLink> BusBoard::Connect() {
  auto link = std::make_unique<Link>(this);
  links_.push_back(link.get());
  return link;
}

void BusBoard::Disconnect(Link* link) { std::erase(links_, link); }

host::BoardClient& BusBoard::client() {
  if (!client_) {
    client_link_ = Connect();
    client_ = std::make_unique<host::BoardClient>(client_link_.get(), node_,
                                                  host::HostHeartbeats::kSend, Clock());
  }
  return *client_;
}

host::BoardClient::Clock BusBoard::Clock() const {
  return [this] {
    const auto ns = std::chrono::nanoseconds(
        static_cast<std::int64_t>(ticks_ * 1'000'000'000u / board_->tick_hz()));
    return std::chrono::steady_clock::time_point(
        std::chrono::duration_cast<std::chrono::steady_clock::duration>(ns));
  };
}

void BusBoard::Run(std::uint64_t ticks) {
  for (std::uint64_t i = 0; i < ticks; ++i) Step();
}

void BusBoard::FromBoard(const protocol::CanFrame& frame) {
  ++sent_[protocol::FunctionOf(frame.id) & 0x7Fu];
  for (Link* link : links_) {
    if (link->Passes(frame)) link->Deliver(frame);
  }
}

void BusBoard::Step() {
  if (before_tick_) before_tick_(*board_);
  board_->Tick();
  ++ticks_;
  if (after_tick_) after_tick_(*board_);
  board_->Poll();
}

}  // namespace mjc::sim
