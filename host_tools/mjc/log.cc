// mjc log: records the bus. candump's log format ("(sec.usec) iface ID#DATA", read by
// can-utils' log2asc and canplayer, Wireshark and python-can) or a CSV of every decoded
// signal in physical units (one row a signal).
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cinttypes>
#include <cstdio>
#include <cstring>
#include <tuple>

#include "commands.h"
#include "mjc/host/can_link.h"
#include "mjc/protocol/codec.h"

namespace mjc::cli {
namespace {

using namespace mjc::protocol;

// "1712345678.000123": the kernel's timestamp, exact to the microsecond.
std::string Seconds(const host::ReceivedFrame& r) {
  char text[32];
  std::snprintf(text, sizeof text, "%010" PRId64 ".%06" PRId64, r.timestamp_us / 1000000,
                r.timestamp_us % 1000000);
  return text;
}

void WriteCandump(std::FILE* out, const std::string& iface,
                  const host::ReceivedFrame& r) {
  std::fprintf(out, "(%s) %s %03X%s", Seconds(r).c_str(), iface.c_str(), r.frame.id,
               r.frame.fd ? "##0" : "#");
  for (int i = 0; i < r.frame.length; ++i)
    std::fprintf(out, "%02X", r.frame.data[static_cast<std::size_t>(i)]);
  std::fputc('\n', out);
}

template <class M>
bool WriteSignals(std::FILE* out, const host::ReceivedFrame& r) {
  if (FunctionOf(r.frame.id) != static_cast<std::uint8_t>(Message<M>::kFunction))
    return false;
  M m;
  if (Decode(r.frame, &m) != DecodeError::kOk) {
    std::fprintf(out, "%s,%03X,%u,%s,malformed,\n", Seconds(r).c_str(), r.frame.id,
                 NodeOf(r.frame.id), Message<M>::kName);
    return true;
  }
  std::apply(
      [&](const auto&... s) {
        ((std::fprintf(
             out, "%s,%03X,%u,%s,%s,%.12g\n", Seconds(r).c_str(), r.frame.id,
             NodeOf(r.frame.id), Message<M>::kName, s.name,
             static_cast<double>(std::decay_t<decltype(s)>::Wire::ToRaw(m.*(s.member))) *
                 s.factor())),
         ...);
      },
      Message<M>::kSignals);
  return true;
}

void WriteCsv(std::FILE* out, const host::ReceivedFrame& r) {
  bool known = false;
  std::apply(
      [&](auto... m) { ((known = known || WriteSignals<decltype(m)>(out, r)), ...); },
      AllMessages{});
  if (!known) {
    std::fprintf(out, "%s,%03X,%u,other,length,%u\n", Seconds(r).c_str(), r.frame.id,
                 NodeOf(r.frame.id), r.frame.length);
  }
}

}  // namespace

void AddLog(CLI::App& app) {
  auto* cmd =
      app.add_subcommand("log", "Record the bus (candump log format or decoded CSV)");
  static std::string iface, format = "candump", out_path;
  static double seconds = 0;
  static long frames = 0;
  AddIfaceOption(cmd, &iface);
  cmd->add_option("--format", format, "candump or csv")
      ->check(CLI::IsMember({"candump", "csv"}))
      ->capture_default_str();
  cmd->add_option("--out", out_path, "Output file (default: stdout)");
  cmd->add_option("--seconds", seconds, "Stop after this long (0: no limit)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--frames", frames, "Stop after this many frames (0: no limit)")
      ->check(CLI::NonNegativeNumber);
  cmd->callback([] {
    std::string why;
    auto link = OpenLink(iface);
    std::FILE* out = out_path.empty() ? stdout : std::fopen(out_path.c_str(), "w");
    if (out == nullptr) {
      throw Failure("cannot write " + out_path + ": " + std::strerror(errno));
    }
    int write_error = 0;  // errno of the first failed write (disk full, closed pipe)
    if (format == "csv" && std::fputs("time_s,id,node,message,signal,value\n", out) < 0)
      write_error = errno;
    const auto deadline =
        std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
    long written = 0;
    bool link_failed = false;
    const auto done = [&] {
      return link_failed || write_error != 0 || (frames > 0 && written >= frames);
    };
    // Writes the next frame that arrives within timeout_ms; false when none did.
    const auto record = [&](int timeout_ms) {
      const auto r = link->Receive(timeout_ms, &why);
      link_failed = r.status == host::ReceiveStatus::kError;
      if (!r) return false;
      if (format == "csv") {
        WriteCsv(out, *r);
      } else {
        WriteCandump(out, iface, *r);
      }
      ++written;
      if (std::ferror(out)) write_error = errno;
      return true;
    };
    // SIGINT/SIGTERM end the recording cleanly: what the socket already holds is still
    // written (for at most a second), the file flushed and the counts printed, so a
    // stopped logger loses nothing it received.
    const std::atomic<bool>& stop = StopOnSignals();
    while (!stop && !done() &&
           (seconds == 0 || std::chrono::steady_clock::now() < deadline)) {
      record(100);
    }
    const auto drain_until = std::chrono::steady_clock::now() + std::chrono::seconds(1);
    while (stop && !done() && std::chrono::steady_clock::now() < drain_until &&
           record(0)) {
    }
    // Buffered lines meet the disk at fflush and fclose.
    if (write_error == 0 && std::fflush(out) != 0) write_error = errno;
    if (out != stdout && std::fclose(out) != 0 && write_error == 0) write_error = errno;
    std::fprintf(stderr, "mjc log: %ld frames, %llu dropped by the kernel\n", written,
                 static_cast<unsigned long long>(link->stats().rx_dropped));
    if (write_error != 0) {
      throw Failure("error writing " + (out_path.empty() ? "stdout" : out_path) + ": " +
                    std::strerror(write_error));
    }
    if (link_failed) throw Failure(why);
  });
}

}  // namespace mjc::cli
