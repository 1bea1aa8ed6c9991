#include "image_file.h"

#include <algorithm>
#include <cinttypes>
#include <cstdio>
#include <fstream>

#include "mjc/protocol/crc32.h"

namespace mjc::boot {

std::vector<std::uint8_t> PackImage(std::span<const std::uint8_t> image,
                                    ImageHeader header) {
  const std::size_t padded = (image.size() + 7) / 8 * 8;
  std::vector<std::uint8_t> file(kHeaderArea + padded, 0xFF);
  std::copy(image.begin(), image.end(), file.begin() + kHeaderArea);
  const auto payload = std::span<const std::uint8_t>(file).subspan(kHeaderArea);
  header.length = static_cast<std::uint32_t>(payload.size());
  header.image_crc = protocol::Crc32(payload);
  const HeaderBytes bytes = EncodeHeader(header);
  std::copy(bytes.begin(), bytes.end(), file.begin());
  return file;
}

bool ReadFileBytes(const std::string& path, std::vector<std::uint8_t>* out) {
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in) return false;
  const std::streamoff size = in.tellg();
  if (size < 0) return false;
  out->assign(static_cast<std::size_t>(size), 0);
  in.seekg(0);
  in.read(reinterpret_cast<char*>(out->data()), static_cast<std::streamsize>(size));
  return static_cast<bool>(in);
}

bool ReadImageFile(const std::string& path, ImageFile* out, std::string* why) {
  ImageFile f;
  if (!ReadFileBytes(path, &f.bytes)) {
    *why = path + ": cannot be read";
    return false;
  }
  f.check = CheckImageFile(f.bytes, &f.header);
  *out = std::move(f);
  return true;
}

std::string DescribeOf(const ImageHeader& header) {
  std::string s;
  for (char c : header.describe) {
    if (c == '\0') break;
    s.push_back(c);
  }
  return s;
}

std::string HeaderTable(const ImageHeader& h) {
  namespace off = header_offset;
  char line[160];
  std::string out;
  const auto row = [&](std::size_t offset, int size, const char* field,
                       const std::string& value) {
    std::snprintf(line, sizeof line, "%6zu %4d  %-26s %s\n", offset, size, field,
                  value.c_str());
    out += line;
  };
  const auto hex = [](std::uint64_t v, int digits) {
    char b[32];
    std::snprintf(b, sizeof b, "0x%0*" PRIX64, digits, v);
    return std::string(b);
  };
  const HeaderBytes b = EncodeHeader(h);
  const auto le32 = [&](std::size_t o) {
    return std::uint32_t{b[o]} | std::uint32_t{b[o + 1]} << 8 |
           std::uint32_t{b[o + 2]} << 16 | std::uint32_t{b[o + 3]} << 24;
  };
  out += "offset size  field                      value\n";
  row(off::kMagic, 4, "magic", hex(kImageMagic, 8) + " \"MJCI\"");
  row(off::kVersion, 2, "format version", std::to_string(kImageFormatVersion));
  row(off::kSize, 2, "header size", std::to_string(kHeaderSize));
  row(off::kBoardType, 2, "board type", std::to_string(h.board_type));
  row(off::kHardwareMin, 1, "hardware revision, lowest", std::to_string(h.hardware_min));
  row(off::kHardwareMax, 1, "hardware revision, highest", std::to_string(h.hardware_max));
  row(off::kLength, 4, "image length", std::to_string(h.length) + " bytes");
  row(off::kImageCrc, 4, "image CRC-32", hex(h.image_crc, 8));
  row(off::kLoadAddress, 4, "load address", hex(h.load_address, 8));
  row(off::kCommit, 4, "build commit", hex(h.commit, 8));
  std::string flags = h.dirty ? "dirty" : "clean";
  if (h.describe_cut) flags += ", describe cut";
  row(off::kFlags, 4, "build flags", flags);
  row(off::kCommitTime, 8, "commit time", std::to_string(h.commit_time_unix) + " s");
  std::string quoted = "\"";
  quoted += DescribeOf(h);
  quoted += '"';
  row(off::kDescribe, static_cast<int>(kDescribeSize), "describe", quoted);
  row(off::kHeaderCrc, 4, "header CRC-32", hex(le32(off::kHeaderCrc), 8));
  row(off::kCommitMark, 4, "commit mark", hex(kCommitMark, 8));
  return out;
}

}  // namespace mjc::boot
