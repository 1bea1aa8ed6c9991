// The candump log format, against lines real can-utils printed.
#include "mjc/host/candump.h"

#include <gtest/gtest.h>
#include <linux/can.h>
#include <linux/can/error.h>

#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "mjc/protocol/codec.h"

namespace {

using namespace mjc;
using namespace mjc::host;

// The candump log format. The lines below are what can-utils' candump -L (2020.11,
// Debian's) printed on vcan0 in the kernel VM for frames sent with cansend, timestamps
// included; the padded and suffixed ones are candump -L recording two interfaces, and
// candump -L -x.

struct RealLine {
  const char* text;
  std::int64_t timestamp_us;
  const char* interface;
  std::uint32_t can_id;
  bool fd;
  std::uint8_t flags;
  std::vector<std::uint8_t> data;  // a remote frame: empty, `length` its DLC
  std::uint8_t length;
  bool canonical;  // candump's own spelling of the frame: formats back identically
};

const RealLine kRealLines[] = {
    {"(1795253289.093369) vcan0 123#DEADBEEF",
     1795253289093369,
     "vcan0",
     0x123,
     false,
     0,
     {0xDE, 0xAD, 0xBE, 0xEF},
     4,
     true},
    {"(1795253289.169273) vcan0 7FF#",
     1795253289169273,
     "vcan0",
     0x7FF,
     false,
     0,
     {},
     0,
     true},
    {"(1795253289.214565) vcan0 000#0011223344556677",
     1795253289214565,
     "vcan0",
     0x000,
     false,
     0,
     {0x00, 0x11, 0x22, 0x33, 0x44, 0x55, 0x66, 0x77},
     8,
     true},
    {"(1795253289.251047) vcan0 12345678#CAFE",
     1795253289251047,
     "vcan0",
     0x12345678 | CAN_EFF_FLAG,
     false,
     0,
     {0xCA, 0xFE},
     2,
     true},
    {"(1795253289.287015) vcan0 1FFFFFFF#01",
     1795253289287015,
     "vcan0",
     0x1FFFFFFF | CAN_EFF_FLAG,
     false,
     0,
     {0x01},
     1,
     true},
    {"(1795253289.342033) vcan0 321#R",
     1795253289342033,
     "vcan0",
     0x321 | CAN_RTR_FLAG,
     false,
     0,
     {},
     0,
     true},
    {"(1795253289.399898) vcan0 321#R3",
     1795253289399898,
     "vcan0",
     0x321 | CAN_RTR_FLAG,
     false,
     0,
     {},
     3,
     true},
    {"(1795253289.439667) vcan0 00000321#R",
     1795253289439667,
     "vcan0",
     0x321 | CAN_EFF_FLAG | CAN_RTR_FLAG,
     false,
     0,
     {},
     0,
     true},
    {"(1795253289.486801) vcan0 123##4",
     1795253289486801,
     "vcan0",
     0x123,
     true,
     CANFD_FDF,
     {},
     0,
     true},
    {"(1795253289.520726) vcan0 123##5AABBCCDD",
     1795253289520726,
     "vcan0",
     0x123,
     true,
     CANFD_FDF | CANFD_BRS,
     {0xAA, 0xBB, 0xCC, 0xDD},
     4,
     true},
    {"(1795253289.550717) vcan0 123##7001122334455667788000000",
     1795253289550717,
     "vcan0",
     0x123,
     true,
     CANFD_FDF | CANFD_BRS | CANFD_ESI,
     {0x00, 0x11, 0x22, 0x33, 0x44, 0x55, 0x66, 0x77, 0x88, 0x00, 0x00, 0x00},
     12,
     true},
    {"(1795253289.617099) vcan0 031#0101",
     1795253289617099,
     "vcan0",
     0x031,
     false,
     0,
     {0x01, 0x01},
     2,
     true},
    {"(1795253306.359001) vcan0 20000004#0004000000000000",
     1795253306359001,
     "vcan0",
     CAN_ERR_FLAG | CAN_ERR_CRTL,
     false,
     0,
     {0x00, 0x04, 0, 0, 0, 0, 0, 0},
     8,
     true},
    {"(1795253298.770858)  vcan0 123#AA",
     1795253298770858,
     "vcan0",
     0x123,
     false,
     0,
     {0xAA},
     1,
     false},
    {"(1795253298.812247) vcan12 456#BB",
     1795253298812247,
     "vcan12",
     0x456,
     false,
     0,
     {0xBB},
     1,
     true},
    {"(1795253298.840401) vcan0 7FF#R8 T",
     1795253298840401,
     "vcan0",
     0x7FF | CAN_RTR_FLAG,
     false,
     0,
     {},
     8,
     false},
};

TEST(CandumpLine, RealCandumpLinesParseAndFormatBack) {
  for (const RealLine& want : kRealLines) {
    std::string why;
    const auto got = ParseCandumpLine(want.text, &why);
    ASSERT_TRUE(got) << want.text << ": " << why;
    EXPECT_EQ(got->timestamp_us, want.timestamp_us) << want.text;
    EXPECT_EQ(got->interface, want.interface) << want.text;
    EXPECT_EQ(got->can_id, want.can_id) << want.text;
    EXPECT_EQ(got->fd, want.fd) << want.text;
    EXPECT_EQ(got->flags, want.flags) << want.text;
    EXPECT_EQ(got->length, want.length) << want.text;
    EXPECT_EQ(got->len8_dlc, 0) << want.text;
    for (std::size_t i = 0; i < got->data.size(); ++i) {
      EXPECT_EQ(got->data[i], i < want.data.size() ? want.data[i] : 0)
          << want.text << " byte " << i;
    }
    if (want.canonical) {
      EXPECT_EQ(FormatCandumpLine(*got), want.text);
    }
    // Any line formats to one that parses back to the same frame.
    const auto again = ParseCandumpLine(FormatCandumpLine(*got), &why);
    ASSERT_TRUE(again) << FormatCandumpLine(*got) << ": " << why;
    EXPECT_EQ(*again, *got) << want.text;
  }
}

TEST(CandumpLine, WhatCansendSpellingsAndOtherWritersAdd) {
  std::string why;
  // cansend's '.' between bytes (candump prints them run together), lower-case hex,
  // a CRLF line end, a tab as the blank, a short seconds field, a received mark.
  const auto dotted = ParseCandumpLine("(1.000001)\tcan0 1ab#11.22.aa R\r\n", &why);
  ASSERT_TRUE(dotted) << why;
  EXPECT_EQ(dotted->timestamp_us, 1000001);
  EXPECT_EQ(dotted->interface, "can0");
  EXPECT_EQ(dotted->can_id, 0x1ABu);
  ASSERT_EQ(dotted->length, 3);
  EXPECT_EQ(dotted->data[2], 0xAA);
  EXPECT_EQ(FormatCandumpLine(*dotted), "(0000000001.000001) can0 1AB#1122AA");
  // Classical 8-byte frames with a raw DLC of 9..15 (newer candump: "_<dlc>").
  const auto dlc =
      ParseCandumpLine("(1699999999.123456) can0 123#0011223344556677_C", &why);
  ASSERT_TRUE(dlc) << why;
  EXPECT_EQ(dlc->length, 8);
  EXPECT_EQ(dlc->len8_dlc, 12);
  EXPECT_EQ(FormatCandumpLine(*dlc), "(1699999999.123456) can0 123#0011223344556677_C");
  const auto remote = ParseCandumpLine("(1699999999.123456) can0 123#R8_F", &why);
  ASSERT_TRUE(remote) << why;
  EXPECT_EQ(remote->length, 8);
  EXPECT_EQ(remote->len8_dlc, 15);
  EXPECT_EQ(FormatCandumpLine(*remote), "(1699999999.123456) can0 123#R8_F");
}

TEST(CandumpLine, MalformedLinesAreRefusedWithTheReason) {
  struct Case {
    std::string line;
    const char* reason;
  };
  const std::string ts = "(1699999999.123456) ";
  const std::vector<Case> cases = {
      {"", "no '(seconds.microseconds)' timestamp"},
      {"1699999999.123456 vcan0 123#00", "no '(seconds.microseconds)' timestamp"},
      {"(1699999999) vcan0 123#00", "want '(seconds.microseconds)'"},
      {"(1699999999.12345) vcan0 123#00", "exactly 6 digits of microseconds"},
      {"(1699999999.1234567) vcan0 123#00", "exactly 6 digits of microseconds, then ')'"},
      {"(1234567890123.000000) vcan0 123#00", "more than 12 digits of seconds"},
      {"(1699999999.123456)vcan0 123#00", "no blank after the timestamp"},
      {ts, "no interface"},
      {ts + "vcan0", "no frame after the interface"},
      {ts + "vcan0 ", "want an id of 3 or 8 hex digits"},
      {ts + "averyverylongname0 123#00", "longer than 15 characters"},
      {ts + std::string("vc\x01n0 123#00"), "control character"},
      {ts + "vcan0 1234#00", "want an id of 3 or 8 hex digits"},
      {ts + "vcan0 12G#00", "the id is not hex"},
      {ts + "vcan0 800#00", "an 11-bit id is at most 7FF"},
      {ts + "vcan0 40000123#00", "a 29-bit id is at most 1FFFFFFF"},
      {ts + "vcan0 E0000004#0000000000000000", "outside CAN_ERR_FLAG | CAN_ERR_MASK"},
      {ts + "vcan0 123#ABC", "odd number of hex digits"},
      {ts + "vcan0 123#001122334455667788", "more than 8 bytes for a classical frame"},
      {ts + "vcan0 123##1" + std::string(130, 'A'), "more than 64 bytes for a CAN FD"},
      {ts + "vcan0 123##", "one hex digit of flags"},
      {ts + "vcan0 123##G00", "one hex digit of flags"},
      {ts + "vcan0 123#R9", "DLC is one digit 0..8"},
      {ts + "vcan0 123#R3AA", "unexpected 'AA'"},
      {ts + "vcan0 20000004#R", "cannot be a remote frame"},
      {ts + "vcan0 20000004##0", "never CAN FD"},
      {ts + "vcan0 123#00112233445566_C", "must follow 8 bytes"},
      {ts + "vcan0 123#0011223344556677_8", "be 9..F"},
      {ts + "vcan0 123#11..22", "'.' in the data not followed by a byte"},
      {ts + "vcan0 123#11 X", "unexpected 'X' after the frame"},
      {ts + "vcan0 123#11 R T", "unexpected 'R T' after the frame"},
  };
  for (const Case& c : cases) {
    std::string why;
    std::optional<CandumpFrame> got;
    EXPECT_NO_THROW(got = ParseCandumpLine(c.line, &why)) << c.line;
    EXPECT_FALSE(got) << c.line;
    EXPECT_NE(why.find(c.reason), std::string::npos) << c.line << "\n  reason: " << why;
  }
}

TEST(CandumpLine, EveryKindOfFrameRoundTrips) {
  std::vector<CandumpFrame> frames;
  CandumpFrame f;
  f.timestamp_us = 1699999999000001;
  f.interface = "can1";
  f.can_id = 0x7FF;
  f.length = 8;
  for (std::uint8_t i = 0; i < 64; ++i) f.data[i] = static_cast<std::uint8_t>(17 * i);
  for (std::size_t i = 8; i < 64; ++i) f.data[i] = 0;
  frames.push_back(f);  // classical, 8 bytes
  f.len8_dlc = 15;
  frames.push_back(f);  // and a raw DLC
  f.len8_dlc = 0;
  f.can_id = 0x1FFFFFFF | CAN_EFF_FLAG;
  f.length = 0;
  f.data = {};
  frames.push_back(f);  // 29-bit, no data
  f.can_id = 0x100 | CAN_RTR_FLAG;
  f.length = 5;
  frames.push_back(f);  // remote, DLC 5
  f.can_id = CAN_ERR_FLAG | CAN_ERR_BUSOFF;
  f.length = 8;
  frames.push_back(f);  // bus-off error frame
  f.can_id = 0x042;
  f.fd = true;
  f.flags = CANFD_BRS | CANFD_FDF;
  f.length = 64;
  for (std::uint8_t i = 0; i < 64; ++i) f.data[i] = static_cast<std::uint8_t>(255 - i);
  frames.push_back(f);  // FD, 64 bytes
  for (const CandumpFrame& frame : frames) {
    const std::string line = FormatCandumpLine(frame);
    std::string why;
    const auto back = ParseCandumpLine(line, &why);
    ASSERT_TRUE(back) << line << ": " << why;
    EXPECT_EQ(*back, frame) << line;
  }
}

TEST(CandumpLine, OnlyStandardDataFramesAreTheProtocols) {
  std::string why;
  const auto ours =
      ParseCandumpLine("(1699999999.123456) vcan0 301#0102030405060708", &why);
  ASSERT_TRUE(ours) << why;
  const auto frame = ToProtocolFrame(*ours);
  ASSERT_TRUE(frame);
  EXPECT_EQ(frame->id, 0x301u);
  EXPECT_EQ(frame->length, 8);
  EXPECT_FALSE(frame->fd);
  EXPECT_EQ(frame->data[7], 0x08);
  for (const char* other : {"(1.000000) vcan0 00000301#01", "(1.000000) vcan0 301#R",
                            "(1.000000) vcan0 20000004#0004000000000000"}) {
    const auto line = ParseCandumpLine(other, &why);
    ASSERT_TRUE(line) << other << ": " << why;
    EXPECT_FALSE(ToProtocolFrame(*line)) << other;
  }
}

// A batch of angle samples as candump -L prints a CAN FD frame with bit-rate switching
// ("##" and the flags digit 1 = CANFD_BRS), written out by hand from the layout
// (messages.h): node 2, first_sample 0x00000105, sample 0 motor raw 0x00010000 (2^-8
// rad) and joint raw -1, sample 4 motor raw 0x7FFFFFFF, the rest zero.
TEST(CandumpLine, ABatchedAngleFrameParsesAndDecodes) {
  const std::string line =
      "(1795253300.000001) vcan0 252##1"
      "05010000"
      "00000100FFFFFFFF"
      "0000000000000000"
      "0000000000000000"
      "0000000000000000"
      "FFFFFF7F00000000"
      "00000000";
  std::string why;
  const auto got = ParseCandumpLine(line, &why);
  ASSERT_TRUE(got) << why;
  EXPECT_TRUE(got->fd);
  EXPECT_EQ(got->flags, CANFD_BRS);
  EXPECT_EQ(got->length, 48);
  EXPECT_EQ(FormatCandumpLine(*got), line);
  const auto frame = ToProtocolFrame(*got);
  ASSERT_TRUE(frame);
  protocol::TelemetryAngleBatch b;
  ASSERT_EQ(protocol::Decode(*frame, &b), protocol::DecodeError::kOk);
  EXPECT_EQ(protocol::NodeOf(frame->id), 2);
  EXPECT_EQ(b.first_sample, 0x105u);
  EXPECT_EQ(b.motor[0].raw(), 0x10000);
  EXPECT_EQ(b.joint[0].raw(), -1);
  EXPECT_EQ(b.motor[4].raw(), 0x7FFFFFFF);
  EXPECT_EQ(b.joint[4].raw(), 0);
  EXPECT_DOUBLE_EQ(b.motor[0].ToDouble(), 1.0 / 256.0);
}

}  // namespace
