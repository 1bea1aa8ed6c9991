// mjc log: records the bus, or decodes a recorded log (--from). Output: candump's log
// format ("(sec.usec) iface ID#DATA", read by can-utils' log2asc and canplayer,
// Wireshark and python-can) or a CSV of every decoded signal in physical units (one row
// a signal). A recorded log is read line by line (host/candump.h): a line that is not
// candump's format is counted and skipped, and the command then fails naming the first.
// Batched angle telemetry (TelemetryAngleBatch, CAN FD) becomes one TelemetryAngles row
// pair a sample in the CSV, with its sample number; a gap in a node's sample count (a
// lost frame) is counted and reported at the end, never filled in.
#include <array>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cinttypes>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iostream>
#include <tuple>
#include <utility>

#include "commands.h"
#include "mjc/host/board_client.h"
#include "mjc/host/can_link.h"
#include "mjc/host/candump.h"
#include "mjc/protocol/codec.h"

namespace mjc::cli {
namespace {

using protocol::AllMessages;
using protocol::CanFrame;
using protocol::DecodeError;
using protocol::FunctionOf;
using protocol::Message;
using protocol::NodeOf;

// "1712345678.000123": a timestamp exact to the microsecond.
std::string Seconds(std::int64_t us) {
  char text[32];
  std::snprintf(text, sizeof text, "%010" PRId64 ".%06" PRId64, us / 1000000,
                us % 1000000);
  return text;
}

template <class M>
bool WriteSignals(std::FILE* out, std::int64_t us, const CanFrame& f) {
  if (FunctionOf(f.id) != static_cast<std::uint8_t>(Message<M>::kFunction)) return false;
  M m;
  if (Decode(f, &m) != DecodeError::kOk) {
    std::fprintf(out, "%s,%03X,%u,%s,malformed,\n", Seconds(us).c_str(), f.id,
                 NodeOf(f.id), Message<M>::kName);
    return true;
  }
  std::apply(
      [&](const auto&... s) {
        ((std::fprintf(
             out, "%s,%03X,%u,%s,%s,%.12g\n", Seconds(us).c_str(), f.id, NodeOf(f.id),
             Message<M>::kName, s.name,
             static_cast<double>(std::decay_t<decltype(s)>::Wire::ToRaw(s.Get(m))) *
                 s.factor())),
         ...);
      },
      Message<M>::kSignals);
  return true;
}

// The batch as the per-sample stream classical frames give: a TelemetryAngles row pair
// a sample, each after its sample number.
bool WriteBatch(std::FILE* out, std::int64_t us, const CanFrame& f) {
  using protocol::TelemetryAngleBatch;
  TelemetryAngleBatch b;
  if (FunctionOf(f.id) !=
          static_cast<std::uint8_t>(Message<TelemetryAngleBatch>::kFunction) ||
      Decode(f, &b) != DecodeError::kOk) {
    return false;  // a malformed one: WriteSignals says so
  }
  const std::string time = Seconds(us);
  const char* name = Message<protocol::TelemetryAngles>::kName;
  for (std::size_t i = 0; i < TelemetryAngleBatch::kSamples; ++i) {
    std::fprintf(out, "%s,%03X,%u,%s,sample,%llu\n", time.c_str(), f.id, NodeOf(f.id),
                 name, static_cast<unsigned long long>(b.first_sample) + i);
    std::fprintf(out, "%s,%03X,%u,%s,motor_angle_rad,%.12g\n", time.c_str(), f.id,
                 NodeOf(f.id), name, b.motor[i].ToDouble());
    std::fprintf(out, "%s,%03X,%u,%s,joint_angle_rad,%.12g\n", time.c_str(), f.id,
                 NodeOf(f.id), name, b.joint[i].ToDouble());
  }
  return true;
}

// Every node's batched angle telemetry, for the gaps in its sample count.
class AngleGaps {
 public:
  void Take(const CanFrame& f) {
    protocol::TelemetryAngleBatch b;
    if (Decode(f, &b) == DecodeError::kOk) nodes_[NodeOf(f.id)].OnBatch(b);
  }
  // ", N angle frame(s) lost (...)" when a node's count had gaps; empty otherwise.
  std::string Summary() const {
    std::string lost;
    for (std::size_t node = 0; node < nodes_.size(); ++node) {
      const host::AngleSequence& s = nodes_[node];
      if (s.lost_frames() == 0) continue;
      lost += (lost.empty() ? "" : ", ") + std::string("node ") + std::to_string(node) +
              ": " + std::to_string(s.lost_frames()) + " (" +
              std::to_string(s.lost_samples()) + " samples)";
    }
    return lost.empty() ? "" : "; batched angle frames lost (gaps in the count): " + lost;
  }

 private:
  std::array<host::AngleSequence, 16> nodes_;
};

void WriteCsv(std::FILE* out, std::int64_t us, const CanFrame& f) {
  if (WriteBatch(out, us, f)) return;
  bool known = false;
  std::apply(
      [&](auto... m) { ((known = known || WriteSignals<decltype(m)>(out, us, f)), ...); },
      AllMessages{});
  if (!known) {
    std::fprintf(out, "%s,%03X,%u,other,length,%u\n", Seconds(us).c_str(), f.id,
                 NodeOf(f.id), f.length);
  }
}

void WriteCandump(std::FILE* out, const host::CandumpFrame& f) {
  std::fputs(host::FormatCandumpLine(f).c_str(), out);
  std::fputc('\n', out);
}

// Where the lines go: --out or stdout, with the first write error kept (disk full, a
// closed pipe) so the command fails naming it instead of losing lines silently.
class Output {
 public:
  explicit Output(const std::string& path) : path_(path) {
    file_ = path.empty() ? stdout : std::fopen(path.c_str(), "w");
    if (file_ == nullptr) {
      throw Failure("cannot write " + path + ": " + std::strerror(errno));
    }
  }
  ~Output() {
    if (file_ != nullptr && file_ != stdout) std::fclose(file_);
  }
  Output(const Output&) = delete;
  Output& operator=(const Output&) = delete;

  std::FILE* file() { return file_; }
  bool failed() {
    if (error_ == 0 && std::ferror(file_)) error_ = errno != 0 ? errno : EIO;
    return error_ != 0;
  }
  // Buffered lines meet the disk at fflush and fclose: throws Failure on any error.
  void Close() {
    failed();
    if (error_ == 0 && std::fflush(file_) != 0) error_ = errno;
    std::FILE* closing = std::exchange(file_, nullptr);
    if (closing != stdout && std::fclose(closing) != 0 && error_ == 0) error_ = errno;
    if (error_ != 0) {
      throw Failure("error writing " + (path_.empty() ? "stdout" : path_) + ": " +
                    std::strerror(error_));
    }
  }

 private:
  std::string path_;
  std::FILE* file_;
  int error_ = 0;
};

// What the subcommand was given.
struct Options {
  std::string iface, format = "candump", out_path, from;
  double seconds = 0;
  long frames = 0;
  bool iface_given = false;  // --from: only this interface's lines
};

void RecordBus(const Options& o) {
  std::string why;
  auto link = OpenLink(o.iface);
  Output out(o.out_path);
  if (o.format == "csv") std::fputs("time_s,id,node,message,signal,value\n", out.file());
  const auto deadline =
      std::chrono::steady_clock::now() + std::chrono::duration<double>(o.seconds);
  long written = 0;
  bool link_failed = false;
  AngleGaps gaps;
  const auto done = [&] {
    return link_failed || out.failed() || (o.frames > 0 && written >= o.frames);
  };
  // Writes the next frame that arrives within timeout_ms; false when none did.
  const auto record = [&](int timeout_ms) {
    const auto r = link->Receive(timeout_ms, &why);
    link_failed = r.failed();
    if (!r) return false;
    gaps.Take(r->frame);
    if (o.format == "csv") {
      WriteCsv(out.file(), r->timestamp_us, r->frame);
    } else {
      host::CandumpFrame line;
      line.timestamp_us = r->timestamp_us;
      line.interface = o.iface;
      line.can_id = r->frame.id;
      line.fd = r->frame.fd;
      line.flags = r->flags;
      line.length = r->frame.length;
      line.data = r->frame.data;
      WriteCandump(out.file(), line);
    }
    ++written;
    return true;
  };
  // SIGINT/SIGTERM end the recording cleanly: what the socket already holds is still
  // written, the file flushed and the counts printed, so a stopped logger loses nothing
  // it received. The drain ends when the socket is empty (it empties faster than any
  // bus fills it), not after a time: on a slow machine writing the backlog takes long.
  const std::atomic<bool>& stop = StopOnSignals();
  while (!stop && !done() &&
         (o.seconds == 0 || std::chrono::steady_clock::now() < deadline)) {
    record(100);
  }
  while (stop && !done() && record(0)) {
  }
  std::fprintf(stderr, "mjc log: %ld frames, %llu dropped by the kernel%s\n", written,
               static_cast<unsigned long long>(link->stats().rx_dropped),
               gaps.Summary().c_str());
  out.Close();
  if (link_failed) throw Failure(why);
}

void DecodeLog(const Options& o) {
  std::ifstream file;
  if (o.from != "-") {
    file.open(o.from);
    if (!file) throw Failure("cannot read " + o.from + ": " + std::strerror(errno));
  }
  std::istream& in = o.from == "-" ? std::cin : file;
  const std::string name = o.from == "-" ? "stdin" : o.from;
  Output out(o.out_path);
  if (o.format == "csv") std::fputs("time_s,id,node,message,signal,value\n", out.file());
  long number = 0, written = 0, malformed = 0, other_iface = 0, not_ours = 0;
  AngleGaps gaps;
  std::string first_malformed;
  const std::atomic<bool>& stop = StopOnSignals();
  for (std::string text; !stop && !out.failed() &&
                         (o.frames == 0 || written < o.frames) &&
                         std::getline(in, text);) {
    ++number;
    std::string why;
    const auto line = host::ParseCandumpLine(text, &why);
    if (!line) {
      if (malformed++ == 0)
        first_malformed = "line " + std::to_string(number) + ": " + why;
      continue;
    }
    if (o.iface_given && line->interface != o.iface) {
      ++other_iface;
      continue;
    }
    const auto frame = host::ToProtocolFrame(*line);
    if (frame) gaps.Take(*frame);
    if (o.format == "csv") {
      if (!frame) {
        ++not_ours;
        continue;
      }
      WriteCsv(out.file(), line->timestamp_us, *frame);
    } else {
      WriteCandump(out.file(), *line);
    }
    ++written;
  }
  if (in.bad()) throw Failure("error reading " + name + ": " + std::strerror(errno));
  std::string counts = "mjc log: " + std::to_string(written) + " frames from " + name;
  if (other_iface > 0) {
    counts += ", " + std::to_string(other_iface) + " of other interfaces skipped";
  }
  if (not_ours > 0) {
    counts += ", " + std::to_string(not_ours) +
              " remote, error or 29-bit frames skipped (not the protocol's)";
  }
  std::fprintf(stderr, "%s%s\n", counts.c_str(), gaps.Summary().c_str());
  out.Close();
  if (malformed > 0) {
    throw Failure(name + ": " + std::to_string(malformed) +
                  " malformed line(s) skipped, the rest decoded (first, " +
                  first_malformed + ")");
  }
}

}  // namespace

void AddLog(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "log",
      "Record the bus, or decode a recorded candump log (candump log format or CSV)");
  static Options o;
  auto* iface = AddIfaceOption(
      cmd, &o.iface, "CAN interface (with --from: decode only its lines; default all)");
  auto* from = cmd->add_option("--from", o.from,
                               "Read a candump log (candump -L, or mjc log's own; - for "
                               "stdin) instead of the bus");
  cmd->add_option("--format", o.format, "candump or csv")
      ->check(CLI::IsMember({"candump", "csv"}))
      ->capture_default_str();
  cmd->add_option("--out", o.out_path, "Output file (default: stdout)");
  cmd->add_option("--seconds", o.seconds, "Stop after this long (0: no limit)")
      ->check(CLI::NonNegativeNumber)
      ->excludes(from);
  cmd->add_option("--frames", o.frames, "Stop after this many frames (0: no limit)")
      ->check(CLI::NonNegativeNumber);
  cmd->callback([iface] {
    o.iface_given = iface->count() > 0;
    if (o.from.empty()) {
      RecordBus(o);
    } else {
      DecodeLog(o);
    }
  });
}

}  // namespace mjc::cli
