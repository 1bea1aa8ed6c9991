// estop_to_stop_frame_ms, for ./bench (run by tests/kernel/gpio.sh inside the VM, with
// `mjc estop` watching the test GPIO chip's line): the time from the edge on the
// emergency-stop line to the StopAll frame on the bus. Each press writes "1" to the
// line's debugfs input (the test chip raises the edge's interrupt within that write)
// after reading CLOCK_MONOTONIC; the StopAll's time is the kernel's receive timestamp on
// a raw CAN socket of the same interface (CLOCK_REALTIME, turned into CLOCK_MONOTONIC
// with the offset between the two read just before the press). Between presses the
// line is released and the watch's repeats (every 100 ms while held) are let pass.
// Prints the median and the range; a figure, asserted nowhere.
//
// usage: estop_latency INPUT IFACE PRESSES   (INPUT: the line's debugfs "input" file)
#include <linux/can.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <poll.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

namespace {

std::int64_t Now(clockid_t clock) {
  timespec t{};
  clock_gettime(clock, &t);
  return std::int64_t{t.tv_sec} * 1000000000 + t.tv_nsec;
}

bool WriteLevel(const char* path, char level) {
  FILE* f = std::fopen(path, "w");
  if (f == nullptr) return false;
  const bool ok = std::fputc(level, f) != EOF;
  return std::fclose(f) == 0 && ok;
}

// The next StopAll on `fd` within `timeout_ms` (-1: none came): its kernel receive time,
// CLOCK_REALTIME ns.
std::int64_t NextStopAll(int fd, int timeout_ms) {
  for (;;) {
    pollfd p{fd, POLLIN, 0};
    const int n = poll(&p, 1, timeout_ms);
    if (n <= 0) return -1;
    can_frame frame{};
    char control[CMSG_SPACE(sizeof(timespec))];
    iovec io{&frame, sizeof frame};
    msghdr msg{};
    msg.msg_iov = &io;
    msg.msg_iovlen = 1;
    msg.msg_control = control;
    msg.msg_controllen = sizeof control;
    if (recvmsg(fd, &msg, 0) < 0) return -1;
    std::int64_t at = -1;
    for (cmsghdr* c = CMSG_FIRSTHDR(&msg); c != nullptr; c = CMSG_NXTHDR(&msg, c)) {
      if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SCM_TIMESTAMPNS) {
        timespec t{};
        std::memcpy(&t, CMSG_DATA(c), sizeof t);
        at = std::int64_t{t.tv_sec} * 1000000000 + t.tv_nsec;
      }
    }
    // Identifier 0, six bytes, "STOP": nothing else counts.
    if (frame.can_id == 0 && frame.len == 6 && std::memcmp(frame.data, "STOP", 4) == 0) {
      return at;
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 4) {
    std::fprintf(stderr, "usage: estop_latency INPUT IFACE PRESSES\n");
    return 2;
  }
  const char* input = argv[1];
  const int presses = std::atoi(argv[3]);
  const int fd = socket(PF_CAN, SOCK_RAW, CAN_RAW);
  if (fd < 0) {
    std::perror("estop_latency: socket");
    return 1;
  }
  const can_filter only_stop{0x000, CAN_SFF_MASK | CAN_EFF_FLAG | CAN_RTR_FLAG};
  const int on = 1;
  setsockopt(fd, SOL_CAN_RAW, CAN_RAW_FILTER, &only_stop, sizeof only_stop);
  setsockopt(fd, SOL_SOCKET, SO_TIMESTAMPNS, &on, sizeof on);
  sockaddr_can addr{};
  addr.can_family = AF_CAN;
  addr.can_ifindex = static_cast<int>(if_nametoindex(argv[2]));
  if (addr.can_ifindex == 0 ||
      bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0) {
    std::fprintf(stderr, "estop_latency: %s: %s\n", argv[2], std::strerror(errno));
    return 1;
  }
  // The cap only ends a wait for a frame that will not come (as the kernel scripts'
  // MJC_WAIT_CAP_S).
  const char* cap = std::getenv("MJC_WAIT_CAP_S");
  const int cap_ms = 1000 * (cap != nullptr ? std::atoi(cap) : 300);
  std::vector<double> ms;
  for (int i = 0; i < presses; ++i) {
    // Released, and whatever the last press's repeats sent drained.
    if (!WriteLevel(input, '0')) {
      std::fprintf(stderr, "estop_latency: cannot write %s\n", input);
      return 1;
    }
    usleep(300000);
    while (NextStopAll(fd, 0) >= 0) {
    }
    const std::int64_t offset = Now(CLOCK_REALTIME) - Now(CLOCK_MONOTONIC);
    const std::int64_t edge = Now(CLOCK_MONOTONIC);
    if (!WriteLevel(input, '1')) return 1;
    const std::int64_t at = NextStopAll(fd, cap_ms);
    if (at < 0) {
      std::fprintf(stderr, "estop_latency: no StopAll after press %d\n", i + 1);
      return 1;
    }
    ms.push_back(static_cast<double>(at - offset - edge) / 1e6);
  }
  WriteLevel(input, '0');
  std::sort(ms.begin(), ms.end());
  std::printf(
      "estop_to_stop_frame_ms: %.2f ms (median of %zu presses, %.2f to %.2f; the "
      "emergency-stop line's edge to the StopAll on vcan0, mjc estop in the VM)\n",
      ms[ms.size() / 2], ms.size(), ms.front(), ms.back());
  return 0;
}
