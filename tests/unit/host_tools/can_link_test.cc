// The host's CAN links without a CAN kernel: the in-process bus (delivery to the other
// links in order, filters, timeouts) and SocketCAN's refusal with a reason where the
// kernel or the interface is missing. The real SocketCAN and ISO-TP paths run against
// Debian's kernel in tests/kernel.
#include "mjc/host/can_link.h"

#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <string>
#include <vector>

namespace {

using namespace mjc;
using namespace mjc::host;

protocol::CanFrame Frame(std::uint32_t id, std::uint8_t byte) {
  protocol::CanFrame f;
  f.id = id;
  f.length = 1;
  f.data[0] = byte;
  return f;
}

TEST(InProcessBus, DeliversToTheOtherLinksInOrder) {
  auto bus = InProcessBus::Create();
  auto a = bus->Connect();
  auto b = bus->Connect();
  auto c = bus->Connect();
  std::string why;
  for (std::uint8_t i = 0; i < 10; ++i) ASSERT_TRUE(a->Send(Frame(0x201, i), &why));
  for (std::uint8_t i = 0; i < 10; ++i) {
    const auto got_b = b->Receive(100);
    const auto got_c = c->Receive(100);
    ASSERT_TRUE(got_b && got_c);
    EXPECT_EQ(got_b->frame.data[0], i);
    EXPECT_EQ(got_c->frame.data[0], i);
  }
  EXPECT_FALSE(a->Receive(0));  // a sender does not hear itself
  EXPECT_EQ(a->stats().sent, 10u);
  EXPECT_EQ(b->stats().received, 10u);
}

TEST(InProcessBus, FiltersAndTimeouts) {
  auto bus = InProcessBus::Create();
  auto host = bus->Connect();
  auto board = bus->Connect();
  std::string why;
  // The host listens to node 3 only.
  const IdFilter node3{0x003, 0x00F};
  ASSERT_TRUE(host->SetFilters({&node3, 1}, &why));
  board->Send(Frame(protocol::MakeId(0x30, 2), 1), &why);
  board->Send(Frame(protocol::MakeId(0x30, 3), 2), &why);
  const auto got = host->Receive(100);
  ASSERT_TRUE(got);
  EXPECT_EQ(got->frame.data[0], 2);
  const auto none = host->Receive(20);
  EXPECT_FALSE(none);
  EXPECT_EQ(none.status, ReceiveStatus::kTimeout);  // a quiet bus is not an error
}

TEST(InProcessBus, TimestampsAreMicrosecondsOfTheRealtimeClock) {
  auto bus = InProcessBus::Create();
  auto a = bus->Connect();
  auto b = bus->Connect();
  std::string why;
  const auto before = std::chrono::duration_cast<std::chrono::microseconds>(
                          std::chrono::system_clock::now().time_since_epoch())
                          .count();
  ASSERT_TRUE(a->Send(Frame(0x201, 1), &why));
  const auto got = b->Receive(100);
  ASSERT_TRUE(got);
  EXPECT_GE(got->timestamp_us, before);
  EXPECT_LT(got->timestamp_us, before + 1000000);
}

TEST(SocketCanLink, RefusesWithAReasonWhenThereIsNoCan) {
  std::string why;
  // This build machine's kernel has no CAN (tests/kernel boots one that has); on a
  // machine with CAN the interface name below does not exist either.
  auto link = SocketCanLink::Open("mjcnosuchcan0", &why);
  EXPECT_EQ(link, nullptr);
  EXPECT_FALSE(why.empty());
  EXPECT_TRUE(why.find("CAN") != std::string::npos ||
              why.find("mjcnosuchcan0") != std::string::npos)
      << why;
  auto isotp = IsoTpLink::Open("", 0x3E1, 0x3F1, &why);
  EXPECT_EQ(isotp, nullptr);
  EXPECT_NE(why.find("interface name"), std::string::npos) << why;
}

// The loopback interface exists on every Linux machine and is no CAN one: named for what
// it is, not "No such device" (bind()'s errno for it).
TEST(SocketCanLink, AnInterfaceThatIsNotCanIsNamedForWhatItIs) {
  if (!std::filesystem::exists("/sys/class/net/lo/type")) GTEST_SKIP() << "no sysfs";
  std::string why;
  EXPECT_EQ(SocketCanLink::Open("lo", &why), nullptr);
  EXPECT_EQ(why.rfind("'lo' is not a CAN interface (it is a loopback device)", 0), 0u)
      << why;
  EXPECT_EQ(IsoTpLink::Open("lo", 0x3E1, 0x3F1, &why), nullptr);
  EXPECT_EQ(why.rfind("'lo' is not a CAN interface", 0), 0u) << why;
}

}  // namespace
