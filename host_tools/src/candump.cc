#include "mjc/host/candump.h"

#include <linux/can.h>
#include <linux/can/error.h>
#include <net/if.h>

#include <algorithm>
#include <array>
#include <cinttypes>
#include <cstdio>

namespace mjc::host {
namespace {

static_assert(CAN_MAX_DLEN == 8 && CANFD_MAX_DLEN == 64);
static_assert(std::tuple_size_v<decltype(CandumpFrame::data)> == CANFD_MAX_DLEN);
static_assert(IFNAMSIZ == 16);

constexpr std::size_t kMaxInterfaceName = IFNAMSIZ - 1;
constexpr std::size_t kMaxSecondsDigits = 12;  // keeps µs since the epoch in an int64
constexpr std::uint8_t kMaxRawDlc = 15;        // CAN_MAX_RAW_DLC (newer linux/can.h)

int HexDigit(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  return -1;
}

bool IsBlank(char c) { return c == ' ' || c == '\t'; }

// Text for a reason: printable characters as they are, others as \xNN.
std::string Shown(std::string_view text) {
  std::string out;
  for (const char c : text.substr(0, 24)) {
    if (c >= 0x20 && c < 0x7F) {
      out += c;
    } else {
      char hex[8];
      std::snprintf(hex, sizeof hex, "\\x%02X", static_cast<unsigned char>(c));
      out += hex;
    }
  }
  if (text.size() > 24) out += "...";
  return out;
}

// Consumes a run of blanks; how many there were.
std::size_t SkipBlanks(std::string_view text, std::size_t* at) {
  const std::size_t start = *at;
  while (*at < text.size() && IsBlank(text[*at])) ++*at;
  return *at - start;
}

// The next field: everything up to a blank or the end.
std::string_view Field(std::string_view text, std::size_t* at) {
  const std::size_t start = *at;
  while (*at < text.size() && !IsBlank(text[*at])) ++*at;
  return text.substr(start, *at - start);
}

// "(seconds.microseconds)" at the start of `line`, into *us.
bool ParseTimestamp(std::string_view line, std::size_t* at, std::int64_t* us,
                    std::string* reason) {
  if (line.empty() || line[0] != '(') {
    *reason = "no '(seconds.microseconds)' timestamp at the start";
    return false;
  }
  std::size_t i = 1;
  std::int64_t seconds = 0;
  std::size_t digits = 0;
  for (; i < line.size() && line[i] >= '0' && line[i] <= '9'; ++i, ++digits) {
    if (digits == kMaxSecondsDigits) {
      *reason = "timestamp: more than 12 digits of seconds";
      return false;
    }
    seconds = seconds * 10 + (line[i] - '0');
  }
  if (digits == 0 || i >= line.size() || line[i] != '.') {
    *reason = "timestamp: want '(seconds.microseconds)', found '" + Shown(line) + "'";
    return false;
  }
  ++i;
  std::int64_t micro = 0;
  for (int n = 0; n < 6; ++n, ++i) {
    if (i >= line.size() || line[i] < '0' || line[i] > '9') {
      *reason = "timestamp: want exactly 6 digits of microseconds";
      return false;
    }
    micro = micro * 10 + (line[i] - '0');
  }
  if (i >= line.size() || line[i] != ')') {
    *reason = "timestamp: want exactly 6 digits of microseconds, then ')'";
    return false;
  }
  *us = seconds * 1000000 + micro;
  *at = i + 1;
  return true;
}

// `text` as hex digits: the value, or -1 when a character is not a hex digit.
std::int64_t HexValue(std::string_view text) {
  std::int64_t value = 0;
  for (const char c : text) {
    const int d = HexDigit(c);
    if (d < 0) return -1;
    value = value * 16 + d;
  }
  return value;
}

// Data bytes as pairs of hex digits, each optionally after a '.', up to `max` of them;
// stops at the first character that begins neither a pair nor a separator.
bool ParseData(std::string_view text, std::size_t* at, std::size_t max, CandumpFrame* f,
               std::string* reason) {
  std::size_t i = *at;
  std::size_t n = 0;
  while (i < text.size()) {
    const bool separated = text[i] == '.' && n > 0;
    const std::size_t pair = separated ? i + 1 : i;
    if (pair >= text.size() || HexDigit(text[pair]) < 0) {
      if (separated) {
        *reason = "a '.' in the data not followed by a byte";
        return false;
      }
      break;
    }
    if (pair + 1 >= text.size() || HexDigit(text[pair + 1]) < 0) {
      *reason = "data: an odd number of hex digits";
      return false;
    }
    if (n == max) {
      *reason = "data: more than " + std::to_string(max) + " bytes for a " +
                (f->fd ? "CAN FD" : "classical") + " frame";
      return false;
    }
    f->data[n++] =
        static_cast<std::uint8_t>(HexDigit(text[pair]) * 16 + HexDigit(text[pair + 1]));
    i = pair + 2;
  }
  f->length = static_cast<std::uint8_t>(n);
  *at = i;
  return true;
}

// "_D" after 8 bytes (or a remote frame's DLC 8): the raw DLC 9..15.
bool ParseLen8Dlc(std::string_view text, std::size_t* at, CandumpFrame* f,
                  std::string* reason) {
  if (*at >= text.size() || text[*at] != '_') return true;
  const int dlc = *at + 1 < text.size() ? HexDigit(text[*at + 1]) : -1;
  if (f->length != CAN_MAX_DLEN || dlc <= CAN_MAX_DLEN) {
    *reason = "a '_' DLC must follow 8 bytes and be 9..F";
    return false;
  }
  f->len8_dlc = static_cast<std::uint8_t>(dlc);
  *at += 2;
  return true;
}

// "<id>#<data>", "<id>#R[<dlc>]" or "<id>##<flags><data>".
bool ParseFrame(std::string_view text, CandumpFrame* f, std::string* reason) {
  const std::size_t hash = text.find('#');
  if (hash != 3 && hash != 8) {
    *reason = "frame '" + Shown(text) + "': want an id of 3 or 8 hex digits, then '#'";
    return false;
  }
  const std::int64_t id = HexValue(text.substr(0, hash));
  if (id < 0) {
    *reason = "frame '" + Shown(text) + "': the id is not hex";
    return false;
  }
  const auto raw_id = static_cast<std::uint32_t>(id);
  const bool error = hash == 8 && (raw_id & CAN_ERR_FLAG) != 0;
  if (hash == 3) {
    if (raw_id > CAN_SFF_MASK) {
      *reason = "an 11-bit id is at most 7FF, not " + std::string(text.substr(0, 3));
      return false;
    }
    f->can_id = raw_id;
  } else if (error) {
    if ((raw_id & ~(CAN_ERR_FLAG | CAN_ERR_MASK)) != 0) {
      *reason = "error frame id " + std::string(text.substr(0, 8)) +
                " has bits outside CAN_ERR_FLAG | CAN_ERR_MASK";
      return false;
    }
    f->can_id = raw_id;
  } else {
    if (raw_id > CAN_EFF_MASK) {
      *reason = "a 29-bit id is at most 1FFFFFFF, not " + std::string(text.substr(0, 8));
      return false;
    }
    f->can_id = raw_id | CAN_EFF_FLAG;
  }

  std::size_t at = hash + 1;
  if (at < text.size() && (text[at] == 'R' || text[at] == 'r')) {
    if (error) {
      *reason = "an error frame cannot be a remote frame";
      return false;
    }
    f->can_id |= CAN_RTR_FLAG;
    ++at;
    if (at < text.size() && text[at] != '_') {
      const int dlc = HexDigit(text[at]);
      if (dlc < 0 || dlc > CAN_MAX_DLEN) {
        *reason = "a remote frame's DLC is one digit 0..8, not '" +
                  Shown(text.substr(at)) + "'";
        return false;
      }
      f->length = static_cast<std::uint8_t>(dlc);
      ++at;
    }
    if (!ParseLen8Dlc(text, &at, f, reason)) return false;
  } else if (at < text.size() && text[at] == '#') {
    if (error) {
      *reason = "an error frame is never CAN FD";
      return false;
    }
    f->fd = true;
    const int flags = at + 1 < text.size() ? HexDigit(text[at + 1]) : -1;
    if (flags < 0) {
      *reason =
          "CAN FD frame '" + Shown(text) + "': want one hex digit of flags after '##'";
      return false;
    }
    f->flags = static_cast<std::uint8_t>(flags);
    at += 2;
    if (!ParseData(text, &at, CANFD_MAX_DLEN, f, reason)) return false;
  } else {
    if (!ParseData(text, &at, CAN_MAX_DLEN, f, reason)) return false;
    if (!ParseLen8Dlc(text, &at, f, reason)) return false;
  }
  if (at != text.size()) {
    *reason = "frame '" + Shown(text) + "': unexpected '" + Shown(text.substr(at)) + "'";
    return false;
  }
  return true;
}

}  // namespace

std::optional<CandumpFrame> ParseCandumpLine(std::string_view line, std::string* why) {
  std::string reason;
  const auto fail = [&]() -> std::optional<CandumpFrame> {
    if (why != nullptr) *why = reason;
    return std::nullopt;
  };
  if (line.ends_with('\n')) line.remove_suffix(1);
  if (line.ends_with('\r')) line.remove_suffix(1);
  CandumpFrame f;
  std::size_t at = 0;
  if (!ParseTimestamp(line, &at, &f.timestamp_us, &reason)) return fail();
  if (SkipBlanks(line, &at) == 0) {
    reason = "no blank after the timestamp";
    return fail();
  }
  const std::string_view interface = Field(line, &at);
  if (interface.empty()) {
    reason = "no interface after the timestamp";
    return fail();
  }
  if (interface.size() > kMaxInterfaceName) {
    reason = "interface '" + Shown(interface) + "' is longer than 15 characters";
    return fail();
  }
  for (const char c : interface) {
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7F) {
      reason = "interface '" + Shown(interface) + "' has a control character";
      return fail();
    }
  }
  f.interface = std::string(interface);
  if (SkipBlanks(line, &at) == 0) {
    reason = "no frame after the interface";
    return fail();
  }
  const std::string_view frame = Field(line, &at);
  if (!ParseFrame(frame, &f, &reason)) return fail();
  // candump -x adds the direction: R received, T sent by this host.
  SkipBlanks(line, &at);
  const std::size_t rest = at;
  const std::string_view extra = Field(line, &at);
  SkipBlanks(line, &at);
  if ((!extra.empty() && extra != "R" && extra != "T") || at != line.size()) {
    reason = "unexpected '" + Shown(line.substr(rest)) + "' after the frame";
    return fail();
  }
  return f;
}

std::string FormatCandumpLine(const CandumpFrame& f) {
  char head[64];
  std::snprintf(head, sizeof head, "(%010" PRId64 ".%06" PRId64 ") ",
                f.timestamp_us / 1000000, f.timestamp_us % 1000000);
  std::string out = head;
  out += f.interface;
  char id[16];
  if (f.can_id & CAN_ERR_FLAG) {
    std::snprintf(id, sizeof id, " %08X#", f.can_id & (CAN_ERR_FLAG | CAN_ERR_MASK));
  } else if (f.can_id & CAN_EFF_FLAG) {
    std::snprintf(id, sizeof id, " %08X#", f.can_id & CAN_EFF_MASK);
  } else {
    std::snprintf(id, sizeof id, " %03X#", f.can_id & CAN_SFF_MASK);
  }
  out += id;
  static constexpr char kHex[] = "0123456789ABCDEF";
  const auto len8_dlc = [&] {
    if (f.length == CAN_MAX_DLEN && f.len8_dlc > CAN_MAX_DLEN &&
        f.len8_dlc <= kMaxRawDlc) {
      out += '_';
      out += kHex[f.len8_dlc];
    }
  };
  if (!f.fd && (f.can_id & CAN_RTR_FLAG)) {
    out += 'R';
    if (f.length > 0 && f.length <= CAN_MAX_DLEN) out += kHex[f.length];
    len8_dlc();
    return out;
  }
  if (f.fd) {
    out += '#';
    out += kHex[f.flags & 0x0F];
  }
  const std::size_t length = std::min<std::size_t>(f.length, f.fd ? 64 : 8);
  for (std::size_t i = 0; i < length; ++i) {
    out += kHex[f.data[i] >> 4];
    out += kHex[f.data[i] & 0x0F];
  }
  if (!f.fd) len8_dlc();
  return out;
}

std::optional<protocol::CanFrame> ToProtocolFrame(const CandumpFrame& f) {
  if (f.can_id & (CAN_EFF_FLAG | CAN_RTR_FLAG | CAN_ERR_FLAG)) return std::nullopt;
  protocol::CanFrame out;
  out.id = f.can_id & CAN_SFF_MASK;
  out.length = f.length;
  out.fd = f.fd;
  out.data = f.data;
  return out;
}

}  // namespace mjc::host
