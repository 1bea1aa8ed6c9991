#include "mjc/host/board_client.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <random>
#include <utility>

#include "mjc/host/describe.h"

namespace mjc::host {

namespace {

// MJC_SILENCE_S when set to a whole number of seconds in 1..3600.
std::optional<std::chrono::milliseconds> SilenceFromEnvironment() {
  static const std::optional<std::chrono::milliseconds> silence =
      []() -> std::optional<std::chrono::milliseconds> {
    const char* text = std::getenv("MJC_SILENCE_S");
    if (text == nullptr || *text == '\0') return std::nullopt;
    char* end = nullptr;
    const long s = std::strtol(text, &end, 10);
    if (*end != '\0' || s < 1 || s > 3600) return std::nullopt;
    return std::chrono::milliseconds{s * 1000};
  }();
  return silence;
}

}  // namespace

std::chrono::milliseconds DefaultSilence() {
  return SilenceFromEnvironment().value_or(std::chrono::milliseconds{10000});
}

std::chrono::milliseconds ExchangeSilence(std::chrono::milliseconds timeout) {
  const auto environment = SilenceFromEnvironment();
  return environment ? std::max(timeout, *environment) : timeout;
}

using protocol::BoardInfo;
using protocol::BoardState;
using protocol::CanFrame;
using protocol::CommandCode;
using protocol::CommandOutcomeCode;
using protocol::DecodeError;
using protocol::Function;
using protocol::FunctionOf;
using protocol::HostHeartbeat;
using protocol::NodeOf;
using protocol::ParamId;
using protocol::ParamRead;
using protocol::ParamStatus;
using protocol::ParamValue;
using protocol::ParamWrite;
using protocol::SentByBoard;
using protocol::SessionId;

void BoardIdentity::OnInfo(const BoardInfo& info) {
  info_since_heartbeat_ = true;
  ++infos_;
  const std::uint16_t id = info.instance;
  const auto known = std::find(instances_.begin(), instances_.end(), id);
  if (known == instances_.end()) {
    instances_.push_back(id);
    infos_heard_.push_back(1);
  } else {
    ++infos_heard_[static_cast<std::size_t>(known - instances_.begin())];
  }
  if (!current_) {
    current_ = id;
  } else if (id != *current_) {
    // One that restarted into another instance and speaks again, or a second new one
    // before the first was judged: two boards.
    if (std::find(retired_.begin(), retired_.end(), id) != retired_.end() ||
        (new_ && *new_ != id)) {
      Sign(id);
    }
    new_ = id;
  }
  info_ = info;
}

void BoardIdentity::OnHeartbeat(std::uint32_t tick) {
  // A board's clock only runs forwards, except across a restart, which it opens with a
  // BoardInfo (sent at its first poll, before its first heartbeat).
  const bool reversed = heartbeats_ > 0 && static_cast<std::int32_t>(tick - tick_) < 0;
  if (new_) {
    // A new instance is a restart when its clock starts anew right after it.
    if (reversed && tick < protocol::kBoardTickHz) {
      retired_.push_back(*current_);
      current_ = new_;
    } else {
      Sign(*new_);
    }
    new_.reset();
  } else if (reversed && !info_since_heartbeat_ && ++clock_reversals_ >= 2) {
    ambiguous_ = true;  // one may be an older image's restart, not two
  }
  info_since_heartbeat_ = false;
  const std::uint32_t step = tick - tick_;
  if (heartbeats_ > 0 && !reversed && step <= 2 * protocol::kBoardTickHz)
    elapsed_ += step;
  ++heartbeats_;
  tick_ = tick;
}

void BoardIdentity::Sign(std::uint16_t instance) {
  if (!ambiguous_) {
    if (current_) sign_ = {instance, *current_};
    infos_at_sign_ = infos_;
  }
  ambiguous_ = true;
}

bool BoardIdentity::proven() const {
  if (!ambiguous_) return false;
  const auto repeated = std::count_if(infos_heard_.begin(), infos_heard_.end(),
                                      [](int n) { return n >= 2; });
  return repeated >= 2 || clock_reversals_ >= 2;
}

std::string BoardIdentity::Message(int node) const {
  if (!ambiguous_) return "";
  if (!proven() && sign_) {
    // One BoardInfo of a second instance (a clock stepping back is ambiguous only when
    // repeated, and then proof): say what it was, not more.
    const auto hex4 = [](std::uint16_t v) {
      char text[8];
      std::snprintf(text, sizeof text, "%04x", v);
      return std::string(text);
    };
    return "node " + std::to_string(node) +
           " showed a sign of a second board on its node id (a BoardInfo of instance " +
           hex4(sign_->first) + " amid " + hex4(sign_->second) +
           "'s): seen once, which a stray or corrupted frame can also cause (mjc list "
           "shows every board on the bus)";
  }
  std::string who;
  if (instances_.size() >= 2) {
    who = "instances ";
    char hex[8];
    for (std::size_t i = 0; i < instances_.size(); ++i) {
      std::snprintf(hex, sizeof hex, "%04x", instances_[i]);
      who += (i == 0                       ? ""
              : i + 1 == instances_.size() ? " and "
                                           : ", ") +
             std::string(hex);
    }
  } else {
    who = "their heartbeat clocks interleave";
  }
  return "node " + std::to_string(node) + " is answered by two boards (" + who +
         "): give each its own node id";
}

BoardClient::BoardClient(CanLink* link, std::uint8_t node, HostHeartbeats heartbeats,
                         Clock now)
    : link_(link),
      node_(node),
      heartbeats_(heartbeats),
      now_(std::move(now)),
      bus_off_at_start_(link->stats().bus_off),
      bus_off_seen_(bus_off_at_start_) {
  // A session of its own when it supervises: its motions are kept alive by its
  // heartbeats alone. Random, so two tools (or two hosts) rarely share one.
  if (heartbeats_ == HostHeartbeats::kSend) {
    std::random_device random;
    std::uniform_int_distribution<int> pick(1, 0xFFFF);
    session_ = static_cast<SessionId>(pick(random));
  }
  // Only a saving: Handle checks the node itself, so a link that cannot filter works.
  const IdFilter only_node{node, 0x00F};
  std::string why;
  link_->SetFilters({&only_node, 1}, &why);
}

bool BoardClient::Await(const std::function<bool()>& done, const Patience& patience,
                        WaitEnd* end, std::string* why, bool stop_at_a_sign) {
  const auto end_with = [&](WaitEnd e, std::string what) {
    *end = e;
    *why = std::move(what);
    return false;
  };
  auto heard_at = now_();
  auto beat_at = heard_at;
  std::uint64_t frames_seen = frames_;
  std::uint64_t heartbeats_seen = heartbeats_heard_;
  std::optional<std::uint32_t> first_tick;
  const auto board_ticks =
      static_cast<std::uint64_t>(patience.board.count()) * protocol::kBoardTickHz / 1000u;
  const auto stop = [&] { return ambiguous() && (stop_at_a_sign || proven_ambiguous()); };
  for (;;) {
    if (stop()) return end_with(WaitEnd::kAmbiguous, AmbiguityMessage());
    if (motion_mismatch()) return end_with(WaitEnd::kWrongMotion, mismatch_);
    if (done()) return true;
    if (interrupted()) return end_with(WaitEnd::kInterrupted, "interrupted");
    if (!Poll(20, why)) {
      *end = WaitEnd::kLinkFailed;
      return false;
    }
    if (stop()) return end_with(WaitEnd::kAmbiguous, AmbiguityMessage());
    if (motion_mismatch()) return end_with(WaitEnd::kWrongMotion, mismatch_);
    if (done()) return true;
    const auto now = now_();
    if (frames_ != frames_seen) {
      frames_seen = frames_;
      heard_at = now;
    }
    if (heartbeats_heard_ != heartbeats_seen) {
      heartbeats_seen = heartbeats_heard_;
      beat_at = now;
      if (!first_tick) first_tick = status_.tick;
      if (board_ticks != 0 && status_.tick - *first_tick > board_ticks) {
        return end_with(WaitEnd::kBoardTime, "node " + std::to_string(node_) + " ran " +
                                                 std::to_string(patience.board.count()) +
                                                 " ms of its own time without it");
      }
    }
    if (now - heard_at > patience.silence) {
      return end_with(WaitEnd::kSilent, SilenceMessage());
    }
    // Talking without a heartbeat: its clock cannot be read, so the board time bound
    // could never end the wait. Far longer than any heartbeat gap of a board that sends
    // them, however slowly it is simulated.
    if (now - beat_at > std::max(patience.silence, kHeartbeatSilence)) {
      return end_with(WaitEnd::kSilent, NoHeartbeatMessage());
    }
  }
}

bool BoardClient::AwaitMotionEnd(BoardState motion, const std::function<void()>& each,
                                 const Patience& patience, WaitEnd* end,
                                 std::string* why) {
  MotionEnd follow(motion);
  const auto over = [&] {
    if (each) each();
    return follow.Over(status_.state);
  };
  return Await(over, patience, end, why);
}

bool BoardClient::Identify(WaitEnd* end, std::string* why,
                           std::chrono::milliseconds silence) {
  // Counted from the first heartbeat this wait sees, in the board's ticks.
  constexpr auto kTicks = static_cast<std::uint32_t>(kBoardInfoPeriod.count() * 11 / 10 *
                                                     protocol::kBoardTickHz / 1000);
  const std::uint64_t start = identity_.elapsed_ticks();
  // A sign of a second board (one frame) is judged before anything is done: proven once
  // both instances were heard twice, a sign once five more BoardInfo frames came.
  const auto shown = [&] {
    if (identity_.ambiguous()) {
      return identity_.proven() || identity_.infos_since_sign() >= 5;
    }
    return identity_.elapsed_ticks() - start >= kTicks;
  };
  // The board time bound is the condition itself.
  if (!Await(shown, Patience{std::chrono::milliseconds{0}, silence}, end, why,
             /*stop_at_a_sign=*/false)) {
    return false;
  }
  if (ambiguous()) {
    *end = WaitEnd::kAmbiguous;
    *why = AmbiguityMessage();
    return false;
  }
  return true;
}

std::optional<CommandOutcomeCode> BoardClient::Command(CommandCode code, int timeout_ms,
                                                       std::string* why,
                                                       protocol::ConfigDigest config) {
  const std::uint8_t seq = ++sequence_;
  last_result_.reset();
  answer_.reset();
  if (!Send(protocol::Command{code, seq, session_, config}, why)) return std::nullopt;
  // Another tool's answer (its session, or its sequence) is not this one's.
  const auto answered = [&] {
    return last_result_ && last_result_->sequence == seq && last_result_->code == code &&
           last_result_->session == session_;
  };
  const std::chrono::milliseconds timeout{timeout_ms};
  WaitEnd end{};
  if (Await(answered, {timeout, ExchangeSilence(timeout)}, &end, why)) {
    answer_ = last_result_;
    return last_result_->outcome;
  }
  if (end == WaitEnd::kBoardTime) {
    *why = "node " + std::to_string(node_) +
           " talks but did not answer the command within " + std::to_string(timeout_ms) +
           " ms of its own time";
  }
  return std::nullopt;
}

std::string BoardClient::SilenceMessage() const {
  std::string out = SilentNode(node_, link_->Name());
  if (frames_ == 0) return out;
  // It was heard: what it last said tells a board killed or powered off mid-motion
  // from one that never answered.
  out += "; it went quiet after " + std::to_string(frames_) + " frames";
  if (heartbeats_heard_ > 0) {
    out += ", its last heartbeat saying " + std::string(StateName(status_.state));
    if (status_.state == BoardState::kRunning ||
        status_.state == BoardState::kCalibrating) {
      out += " (stopped, reset or powered off mid-motion?)";
    }
  }
  return out;
}

std::string BoardClient::NoHeartbeatMessage() const {
  const std::string who = "node " + std::to_string(node_);
  // A bootloader answers with BootStatus, never a heartbeat.
  if (boot_status_) {
    return who + " is in its bootloader, " + DescribeBootStatus(*boot_status_) +
           ", not its application (mjc flash --node " + std::to_string(node_) +
           " updates or boots it)";
  }
  return who + " sends frames but no heartbeat for " +
         std::to_string(kHeartbeatSilence.count()) +
         " ms: not this application's heartbeat (an older or foreign image on the node?)";
}

std::string BoardClient::RefusalMessage(CommandOutcomeCode outcome) const {
  const std::string who = "node " + std::to_string(node_);
  const auto hex = [](unsigned v, int digits) {
    char text[12];
    std::snprintf(text, sizeof text, "%0*x", digits, v);
    return std::string(text);
  };
  if (answer_ && answer_->outcome == outcome) {
    const protocol::CommandResult& r = *answer_;
    const bool held = outcome == CommandOutcomeCode::kRefusedNotIdle ||
                      outcome == CommandOutcomeCode::kRefusedBusy;
    if (held && r.detail != 0 && r.owner != 0 && r.owner != session_) {
      return who + " is in use by session " + hex(r.owner, 4) + ", started by its " +
             std::string(MotionName(r.detail)) +
             " (another tool's: wait for it to end, or stop it with mjc stop --node " +
             std::to_string(node_) + ")";
    }
    if (held && r.detail != 0 && r.owner == 0) {
      return who + " is in use: a " + std::string(MotionName(r.detail)) +
             " runs, started by a tool without a session (cansend?); stop it with mjc "
             "stop --node " +
             std::to_string(node_);
    }
    if (outcome == CommandOutcomeCode::kRefusedInvalid &&
        r.detail == protocol::kDetailConfigMismatch) {
      return who + " holds another configuration than this session's " +
             hex(bound_config_, 8) + " (" + bound_name_ +
             "): another sender's came in between" +
             (configs_seen_.empty()
                  ? std::string()
                  : " (last seen: " + configs_seen_.back().second + ")");
    }
  }
  return who + " refused: " + std::string(OutcomeName(outcome));
}

template <class Config>
std::optional<CommandOutcomeCode> BoardClient::StartBound(CommandCode code,
                                                          const Config& config,
                                                          int timeout_ms,
                                                          std::string* why) {
  const protocol::ConfigDigest digest = protocol::ConfigDigestOf(config);
  std::optional<CommandOutcomeCode> outcome;
  // A configuration frame of another sender's between ours and the start makes the
  // board refuse it (kDetailConfigMismatch): the pair is sent again, twice at most.
  for (int attempt = 0; attempt < 3; ++attempt) {
    bound_ = true;
    confirmed_ = false;
    bound_code_ = code;
    bound_config_ = digest;
    bound_name_ = DescribeConfig(config);
    mismatch_.clear();
    if (!Send(config, why)) return std::nullopt;
    outcome = Command(code, timeout_ms, why, digest);
    if (!outcome) return std::nullopt;  // unanswered, or answered with another motion
    const bool crossed = *outcome == CommandOutcomeCode::kRefusedInvalid && answer_ &&
                         answer_->detail == protocol::kDetailConfigMismatch;
    if (!crossed) break;
  }
  if (*outcome != CommandOutcomeCode::kAccepted) {
    bound_ = false;
    mismatch_.clear();
    return outcome;
  }
  // The board's first frame of the motion follows its answer at once.
  const std::chrono::milliseconds second{1000};
  WaitEnd end{};
  if (!Await([&] { return confirmed_; }, {second, ExchangeSilence(second)}, &end, why)) {
    if (end == WaitEnd::kBoardTime) {
      Mismatch("node " + std::to_string(node_) +
               " accepted the start but did not say what it runs (no MotionConfig "
               "within 1 s of its time: an older image?); not recording it");
      *why = mismatch_;
    }
    return std::nullopt;
  }
  return outcome;
}

std::optional<CommandOutcomeCode> BoardClient::Start(const protocol::TrialConfig& config,
                                                     int timeout_ms, std::string* why) {
  return StartBound(CommandCode::kStartTrial, config, timeout_ms, why);
}

std::optional<CommandOutcomeCode> BoardClient::Start(const protocol::SweepConfig& config,
                                                     int timeout_ms, std::string* why) {
  return StartBound(CommandCode::kStartSweep, config, timeout_ms, why);
}

void BoardClient::ReleaseMotion() {
  bound_ = false;
  confirmed_ = false;
  mismatch_.clear();
}

void BoardClient::Mismatch(const std::string& what) {
  if (mismatch_.empty()) mismatch_ = what;
}

std::string BoardClient::NameConfig(protocol::ConfigDigest digest) const {
  char hex[12];
  std::snprintf(hex, sizeof hex, "%08x", digest);
  if (digest == bound_config_) return std::string(hex) + " (" + bound_name_ + ")";
  for (auto it = configs_seen_.rbegin(); it != configs_seen_.rend(); ++it) {
    if (it->first == digest) {
      return std::string(hex) + " (" + it->second + ", another sender's)";
    }
  }
  return std::string(hex) + " (not seen on the bus)";
}

template <class Request>
std::optional<ParamValue> BoardClient::AskParam(const Request& request, ParamId id,
                                                int timeout_ms, const char* what,
                                                std::string* why) {
  last_param_.reset();
  if (!Send(request, why)) return std::nullopt;
  const auto answered = [&] { return last_param_ && last_param_->id == id; };
  const std::chrono::milliseconds timeout{timeout_ms};
  WaitEnd end{};
  if (!Await(answered, {timeout, ExchangeSilence(timeout)}, &end, why)) {
    if (end == WaitEnd::kBoardTime) {
      *why = "node " + std::to_string(node_) + " talks but did not answer " + what +
             " within " + std::to_string(timeout_ms) + " ms of its own time";
    }
    return std::nullopt;
  }
  return last_param_;
}

std::optional<std::int32_t> BoardClient::ReadParam(ParamId id, int timeout_ms,
                                                   std::string* why) {
  const auto answer = AskParam(ParamRead{id}, id, timeout_ms, "a parameter read", why);
  if (!answer) return std::nullopt;
  if (answer->status != ParamStatus::kOk) {
    *why = "node " + std::to_string(node_) + " answered parameter " +
           std::to_string(static_cast<int>(id)) + " with status " +
           std::to_string(static_cast<int>(answer->status));
    return std::nullopt;
  }
  return answer->value;
}

std::optional<ParamValue> BoardClient::WriteParam(ParamId id, std::int32_t raw,
                                                  int timeout_ms, std::string* why) {
  return AskParam(ParamWrite{id, raw}, id, timeout_ms, "a parameter write", why);
}

bool BoardClient::Poll(int timeout_ms, std::string* why) {
  using std::chrono::milliseconds;
  const auto deadline = now_() + milliseconds(timeout_ms);
  for (;;) {
    if (!Beat(why)) return false;
    // Wait no longer than the next heartbeat: a long wait is a series of short ones.
    auto until = deadline;
    if (heartbeats_ == HostHeartbeats::kSend) until = std::min(until, next_heartbeat_);
    const auto wait = std::max(std::chrono::ceil<milliseconds>(until - now_()).count(),
                               milliseconds::rep{0});
    ReceiveResult r = link_->Receive(static_cast<int>(wait), why);
    const bool arrived = static_cast<bool>(r);
    for (; r; r = link_->Receive(0, why)) Handle(r->frame);
    NoteBusOff();
    if (r.failed()) {
      link_failed_ = true;
      return false;
    }
    if (arrived || now_() >= deadline) return Beat(why);
  }
}

bool BoardClient::Beat(std::string* why) {
  if (heartbeats_ != HostHeartbeats::kSend) return true;
  const auto now = now_();
  if (now < next_heartbeat_) return true;
  // Keep the cadence when a poll ran a little late; start afresh after a pause.
  next_heartbeat_ = now - next_heartbeat_ < kHostHeartbeatPeriod
                        ? next_heartbeat_ + kHostHeartbeatPeriod
                        : now + kHostHeartbeatPeriod;
  return Send(HostHeartbeat{heartbeat_sequence_++, session_}, why);
}

void BoardClient::NoteBusOff() {
  const std::uint64_t now = link_->stats().bus_off;
  if (now == bus_off_seen_) return;
  bus_off_seen_ = now;
  if (on_bus_off_) on_bus_off_(bus_off());
}

std::vector<BoardWindow> BoardClient::TakeWindows() {
  std::vector<BoardWindow> out;
  out.swap(windows_);
  return out;
}

void AngleSequence::OnBatch(const protocol::TelemetryAngleBatch& batch) {
  constexpr auto kSamples =
      static_cast<std::uint32_t>(protocol::TelemetryAngleBatch::kSamples);
  ++batches_;
  // Modulo 2^32, as the board counts: half the range ahead is a gap, behind a restart.
  const std::uint32_t gap = batch.first_sample - next_;
  if (started_ && gap != 0) {
    if (gap < 0x80000000u) {
      lost_samples_ += gap;
      lost_frames_ += (gap + kSamples - 1) / kSamples;
    } else {
      ++restarts_;
    }
  }
  started_ = true;
  next_ = batch.first_sample + kSamples;
}

std::vector<AngleSample> BoardClient::TakeAngles() {
  std::vector<AngleSample> out;
  out.swap(angles_);
  return out;
}

// A window is kept only when its five parts arrive complete and in order (the board
// sends them back to back, header first, with ascending ids, so the bus keeps the
// order): a lost or refused part drops the window rather than mixing two windows.
bool BoardClient::AcceptWindowPart(int part) {
  const bool in_progress = last_part_ >= 0;
  if (part == 0 || !in_progress || part <= last_part_) {  // a new window
    if (in_progress && !broken_) ++incomplete_windows_;   // the last one never ended
    broken_ = part != 0;                                  // begun without its header
    if (broken_) ++incomplete_windows_;
    if (part == 0) partial_ = BoardWindow{};
  } else if (part != last_part_ + 1 && !broken_) {  // a part skipped
    broken_ = true;
    ++incomplete_windows_;
  }
  const bool keep = !broken_;
  last_part_ = part == kLastWindowPart ? -1 : part;
  if (part == kLastWindowPart) broken_ = false;
  return keep;
}

void BoardClient::Handle(const CanFrame& f) {
  if (NodeOf(f.id) != node_) return;
  if (SentByBoard(FunctionOf(f.id))) ++frames_;
  const auto ok = [this](DecodeError e) {
    if (e == DecodeError::kOk) return true;
    if (e != DecodeError::kWrongFunction) ++malformed_;
    return false;
  };
  switch (static_cast<Function>(FunctionOf(f.id))) {
    case Function::kCommandResult: {
      protocol::CommandResult r;
      if (ok(Decode(f, &r))) last_result_ = r;
      return;
    }
    case Function::kParamValue: {
      ParamValue v;
      if (ok(Decode(f, &v))) last_param_ = v;
      return;
    }
    case Function::kBoardInfo: {
      BoardInfo info;
      if (ok(Decode(f, &info))) identity_.OnInfo(info);
      return;
    }
    case Function::kHeartbeat: {
      protocol::Heartbeat h;
      if (!ok(Decode(f, &h))) return;
      boot_status_.reset();  // the application runs
      identity_.OnHeartbeat(h.tick);
      ++heartbeats_heard_;
      status_.heard = true;
      status_.state = h.state;
      status_.calibrated = h.calibrated;
      status_.fault = h.fault;
      status_.tick = h.tick;
      return;
    }
    case Function::kFault: {
      protocol::FaultEvent e;
      if (ok(Decode(f, &e))) {
        status_.fault = e.fault;
        status_.state = BoardState::kFault;
      }
      return;
    }
    case Function::kTelemetryAngles: {
      protocol::TelemetryAngles a;
      if (ok(Decode(f, &a))) {
        status_.motor_rad = a.motor.ToDouble();
        status_.joint_rad = a.joint.ToDouble();
        if (keep_angles_ && MotionTrusted()) {
          angles_.push_back({status_.motor_rad, status_.joint_rad});
        }
      }
      return;
    }
    case Function::kTelemetryAngleBatch: {
      protocol::TelemetryAngleBatch b;
      if (!ok(Decode(f, &b))) return;
      angle_sequence_.OnBatch(b);
      for (std::size_t i = 0; i < b.motor.size(); ++i) {
        status_.motor_rad = b.motor[i].ToDouble();
        status_.joint_rad = b.joint[i].ToDouble();
        if (keep_angles_ && MotionTrusted()) {
          angles_.push_back({status_.motor_rad, status_.joint_rad});
        }
      }
      return;
    }
    case Function::kTelemetryTorque: {
      protocol::TelemetryTorque t;
      if (ok(Decode(f, &t))) status_.torque_Nm = t.torque.ToDouble();
      return;
    }
    case Function::kTelemetryPower: {
      protocol::TelemetryPower p;
      if (ok(Decode(f, &p))) status_.power_W = p.power.ToDouble();
      return;
    }
    case Function::kTelemetryEnergy: {
      protocol::TelemetryEnergy e;
      if (ok(Decode(f, &e))) status_.energy_J = e.energy.ToDouble();
      return;
    }
    case Function::kWindowStart: {
      protocol::WindowStart w;
      if (!ok(Decode(f, &w))) return;
      if (bound_ && (w.config16 != (bound_config_ & 0xFFFFu) || !confirmed_)) {
        char text[160];
        std::snprintf(text, sizeof text,
                      "node %d began a window of configuration ..%04x, not of this "
                      "session's %s",
                      node_, static_cast<unsigned>(w.config16),
                      NameConfig(bound_config_).c_str());
        Mismatch(text);
      }
      if (on_window_start_ && MotionTrusted()) on_window_start_(w);
      return;
    }
    case Function::kBootStatus: {
      protocol::BootStatus b;
      if (ok(Decode(f, &b))) boot_status_ = b;
      return;
    }
    case Function::kMotionConfig: {
      protocol::MotionConfig m;
      if (!ok(Decode(f, &m)) || !bound_) return;
      // The bound start's motion: this session's, with this configuration, once.
      if (!confirmed_ && m.start == bound_code_ && m.session == session_ &&
          m.config == bound_config_) {
        confirmed_ = true;
        return;
      }
      char session[8];
      std::snprintf(session, sizeof session, "%04x", m.session);
      Mismatch("node " + std::to_string(node_) + " runs a " +
               std::string(MotionName(static_cast<std::uint8_t>(m.start))) +
               " of session " + session + " with configuration " + NameConfig(m.config) +
               ", not this session's " +
               std::string(MotionName(static_cast<std::uint8_t>(bound_code_))) +
               " with configuration " + NameConfig(bound_config_));
      return;
    }
    case Function::kTrialConfig:
    case Function::kSweepConfig: {
      // Another sender's configuration for this node: kept to name what the board runs.
      std::string name;
      protocol::ConfigDigest digest = 0;
      if (FunctionOf(f.id) == static_cast<std::uint8_t>(Function::kTrialConfig)) {
        protocol::TrialConfig c;
        if (Decode(f, &c) != DecodeError::kOk) return;
        digest = protocol::ConfigDigestOf(c);
        name = DescribeConfig(c);
      } else {
        protocol::SweepConfig c;
        if (Decode(f, &c) != DecodeError::kOk) return;
        digest = protocol::ConfigDigestOf(c);
        name = DescribeConfig(c);
      }
      if (configs_seen_.size() >= 8) configs_seen_.erase(configs_seen_.begin());
      configs_seen_.emplace_back(digest, std::move(name));
      return;
    }
    // A window travels as seven frames (see AcceptWindowPart).
    case Function::kWindowHeader: {
      protocol::WindowHeader h;
      if (!ok(Decode(f, &h)) || !AcceptWindowPart(0)) return;
      partial_.motion = h.motion;
      partial_.repetition = h.repetition;
      partial_.eta_valid = h.eta_valid;
      partial_.eta_percent = h.eta_percent.ToDouble();
      partial_.fit_status = static_cast<int>(h.fit_status);
      partial_.fit_valid = h.fit_status == InterfaceFitStatus::kOk;
      return;
    }
    case Function::kWindowEnergy: {
      protocol::WindowEnergy e;
      if (!ok(Decode(f, &e)) || !AcceptWindowPart(1)) return;
      partial_.loading_J = e.loading.ToDouble();
      partial_.unloading_J = e.unloading.ToDouble();
      return;
    }
    case Function::kWindowWork: {
      protocol::WindowWork w;
      if (!ok(Decode(f, &w)) || !AcceptWindowPart(2)) return;
      partial_.positive_J = w.positive.ToDouble();
      partial_.negative_J = w.negative.ToDouble();
      return;
    }
    case Function::kWindowPeaks: {
      protocol::WindowPeaks p;
      if (!ok(Decode(f, &p)) || !AcceptWindowPart(3)) return;
      partial_.peak_power_W = p.peak_power.ToDouble();
      partial_.peak_torque_Nm = p.peak_torque.ToDouble();
      return;
    }
    case Function::kWindowTicks: {
      protocol::WindowTicks t;
      if (!ok(Decode(f, &t)) || !AcceptWindowPart(4)) return;
      partial_.start_tick = t.start_tick;
      partial_.peak_tick = t.start_tick + t.peak_offset;
      partial_.end_tick = t.start_tick + t.end_offset;
      return;
    }
    case Function::kWindowFit: {
      protocol::WindowFit w;
      if (!ok(Decode(f, &w)) || !AcceptWindowPart(5)) return;
      partial_.stiffness_Nm_rad = w.stiffness.ToDouble();
      partial_.damping_Nms_rad = w.damping.ToDouble();
      return;
    }
    case Function::kWindowFitResidual: {
      protocol::WindowFitResidual r;
      if (!ok(Decode(f, &r)) || !AcceptWindowPart(kLastWindowPart)) return;
      partial_.offset_Nm = r.offset.ToDouble();
      partial_.residual_rms_Nm = r.residual_rms.ToDouble();
      // Never a window of a motion this client cannot vouch for.
      if (!MotionTrusted()) {
        ++unbound_windows_;
        if (bound_ && !confirmed_) {
          Mismatch("node " + std::to_string(node_) +
                   " sent a window before it said what it runs");
        }
        return;
      }
      windows_.push_back(partial_);
      return;
    }
    default:
      return;
  }
}

}  // namespace mjc::host
