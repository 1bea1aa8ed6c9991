// mjc-image: puts the image header in front of a linked application image, and shows
// and checks image files. The build runs `pack` after linking each application
// (cmake/package_app_image.cmake); `show` prints a file's header as the table of the
// image format (firmware/bootloader/BOOTLOADER.md).
//
//   mjc-image pack IMAGE.bin OUT.bin --board-type N --hardware MIN MAX
//             --load-address ADDR --commit HEX --dirty 0|1 --commit-time SECONDS
//             --describe TEXT [--flip-byte OFFSET]
//   mjc-image show FILE [--board-type N --hardware-revision R --load-address ADDR
//             --max-length BYTES]
//   mjc-image identity OUT.bin --node N --revision R
//
// `identity` writes a new board's identity pages (node id 1..8, hardware revision
// 1..255; 4,096 bytes for flash at 0x0807E000, pages 252-253) with the bootloader's own
// IdentityStore, for the first flash through the debug connector (scripts/first-flash):
// every board on a bus needs a node id of its own, and updates never touch these pages.
//
// --flip-byte exists for the bootloader's tests: it inverts one byte of the image after
// the header was computed, giving a file whose CRC does not match.
// Exit status: 0 done / valid, 1 the file does not check out, 2 usage or I/O error.
#include <cerrno>
#include <cinttypes>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include "hal/flash.h"
#include "image_file.h"
#include "mjc/boot/identity_store.h"

namespace {

using namespace mjc::boot;

[[noreturn]] void Usage(const char* why) {
  std::fprintf(stderr,
               "mjc-image: %s\n"
               "usage: mjc-image pack IMAGE.bin OUT.bin --board-type N --hardware MIN "
               "MAX --load-address ADDR --commit HEX --dirty 0|1 --commit-time S "
               "--describe TEXT [--flip-byte OFFSET]\n"
               "       mjc-image show FILE [--board-type N --hardware-revision R "
               "--load-address ADDR --max-length BYTES]\n"
               "       mjc-image identity OUT.bin --node N --revision R\n",
               why);
  std::exit(2);
}

std::uint64_t Number(const std::string& text, std::uint64_t max) {
  char* end = nullptr;
  errno = 0;
  const unsigned long long v = std::strtoull(text.c_str(), &end, 0);
  if (text.empty() || *end != '\0' || errno != 0 || v > max) {
    Usage(("not a number in range: '" + text + "'").c_str());
  }
  return v;
}

struct Args {
  std::vector<std::string> positional;
  std::vector<std::pair<std::string, std::vector<std::string>>> options;
  const std::vector<std::string>* Get(const std::string& name) const {
    for (const auto& [n, v] : options) {
      if (n == name) return &v;
    }
    return nullptr;
  }
  std::string One(const std::string& name) const {
    const auto* v = Get(name);
    if (v == nullptr) Usage(("missing " + name).c_str());
    return v->front();
  }
};

Args Parse(int argc, char** argv, int first) {
  Args a;
  for (int i = first; i < argc; ++i) {
    const std::string s = argv[i];
    if (s.rfind("--", 0) != 0) {
      a.positional.push_back(s);
      continue;
    }
    const int n = s == "--hardware" ? 2 : 1;
    if (i + n >= argc) Usage(("missing value for " + s).c_str());
    std::vector<std::string> values;
    for (int k = 1; k <= n; ++k) values.push_back(argv[i + k]);
    a.options.emplace_back(s, values);
    i += n;
  }
  return a;
}

bool WriteAll(const std::string& path, const std::vector<std::uint8_t>& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()),
            static_cast<std::streamsize>(bytes.size()));
  return static_cast<bool>(out);
}

int Pack(const Args& a) {
  if (a.positional.size() != 2) Usage("pack takes IMAGE.bin and OUT.bin");
  std::vector<std::uint8_t> image;
  if (!ReadFileBytes(a.positional[0], &image)) {
    std::fprintf(stderr, "mjc-image: %s: cannot be read\n", a.positional[0].c_str());
    return 2;
  }
  ImageHeader h;
  h.board_type = static_cast<std::uint16_t>(Number(a.One("--board-type"), 0xFFFF));
  const auto* hw = a.Get("--hardware");
  if (hw == nullptr) Usage("missing --hardware");
  h.hardware_min = static_cast<std::uint8_t>(Number((*hw)[0], 0xFF));
  h.hardware_max = static_cast<std::uint8_t>(Number((*hw)[1], 0xFF));
  h.load_address =
      static_cast<std::uint32_t>(Number(a.One("--load-address"), 0xFFFFFFFFu));
  const std::string commit = a.One("--commit");
  h.commit = static_cast<std::uint32_t>(
      Number(commit.rfind("0x", 0) == 0 ? commit : "0x" + commit, 0xFFFFFFFFu));
  h.dirty = Number(a.One("--dirty"), 1) == 1;
  h.commit_time_unix = Number(a.One("--commit-time"), ~std::uint64_t{0});
  const std::string describe = a.One("--describe");
  h.describe_cut = describe.size() > kDescribeSize - 1;
  for (std::size_t i = 0; i < describe.size() && i + 1 < kDescribeSize; ++i) {
    h.describe[i] = describe[i];
  }
  // The image must open with a vector table for its own load address: an initial
  // stack pointer, then a Thumb reset handler inside the image.
  if (image.size() < 8) {
    std::fprintf(stderr, "mjc-image: %s: %zu bytes, no vector table\n",
                 a.positional[0].c_str(), image.size());
    return 1;
  }
  const std::uint32_t reset = std::uint32_t{image[4]} | std::uint32_t{image[5]} << 8 |
                              std::uint32_t{image[6]} << 16 |
                              std::uint32_t{image[7]} << 24;
  if ((reset & 1u) == 0 || reset < h.load_address ||
      reset - h.load_address >= image.size()) {
    std::fprintf(stderr,
                 "mjc-image: %s: reset vector 0x%08" PRIX32
                 " is not a Thumb address inside an image loaded at 0x%08" PRIX32 "\n",
                 a.positional[0].c_str(), reset, h.load_address);
    return 1;
  }
  std::vector<std::uint8_t> file = PackImage(image, h);
  if (const auto* flip = a.Get("--flip-byte")) {
    const std::uint64_t offset = Number(flip->front(), file.size() - kHeaderArea - 1);
    file[kHeaderArea + offset] ^= 0xFFu;
  }
  if (!WriteAll(a.positional[1], file)) {
    std::fprintf(stderr, "mjc-image: %s: cannot be written\n", a.positional[1].c_str());
    return 2;
  }
  ImageHeader written;
  (void)CheckImageFile(file, &written);
  std::printf("mjc-image: %s: %zu bytes (image %" PRIu32 " bytes, CRC-32 0x%08" PRIX32
              ", %s%s)\n",
              a.positional[1].c_str(), file.size(), written.length, written.image_crc,
              DescribeOf(written).c_str(),
              a.Get("--flip-byte") ? ", one byte flipped" : "");
  return 0;
}

int Show(const Args& a) {
  if (a.positional.size() != 1) Usage("show takes one FILE");
  ImageFile f;
  std::string why;
  if (!ReadImageFile(a.positional[0], &f, &why)) {
    std::fprintf(stderr, "mjc-image: %s\n", why.c_str());
    return 2;
  }
  if (f.check != ImageCheck::kNoImage && f.check != ImageCheck::kBadHeader) {
    std::fputs(HeaderTable(f.header).c_str(), stdout);
  }
  ImageCheck check = f.check;
  if (check == ImageCheck::kValid && a.Get("--board-type") != nullptr) {
    ImageTarget t;
    t.board_type = static_cast<std::uint16_t>(Number(a.One("--board-type"), 0xFFFF));
    t.hardware_revision =
        static_cast<std::uint8_t>(Number(a.One("--hardware-revision"), 0xFF));
    t.load_address =
        static_cast<std::uint32_t>(Number(a.One("--load-address"), 0xFFFFFFFFu));
    t.max_length = static_cast<std::uint32_t>(Number(a.One("--max-length"), 0xFFFFFFFFu));
    check = CheckHeaderFor(f.header, t);
  }
  std::printf("%s: %s\n", a.positional[0].c_str(), ImageCheckName(check));
  return check == ImageCheck::kValid ? 0 : 1;
}

// Two erased flash pages in memory: the identity pages as the board's flash will hold
// them, written through the same IdentityStore the bootloader reads them with.
class PagesInMemory final : public mjc::hal::Flash {
 public:
  std::vector<std::uint8_t> bytes = std::vector<std::uint8_t>(2 * kPageSize, 0xFF);

 private:
  mjc::hal::FlashResult DoErasePage(std::uint32_t page) override {
    if (page >= 2) return mjc::hal::FlashResult::kBadAddress;
    std::memset(bytes.data() + page * kPageSize, 0xFF, kPageSize);
    return mjc::hal::FlashResult::kOk;
  }
  mjc::hal::FlashResult DoProgram(std::uint32_t page, std::uint32_t offset,
                                  std::uint64_t value) override {
    if (page >= 2 || offset % kDoubleWord != 0 || offset >= kPageSize) {
      return mjc::hal::FlashResult::kBadAddress;
    }
    std::uint8_t* at = bytes.data() + page * kPageSize + offset;
    for (std::size_t i = 0; i < kDoubleWord; ++i) {
      if (at[i] != 0xFF) return mjc::hal::FlashResult::kNotErased;
    }
    for (std::size_t i = 0; i < kDoubleWord; ++i) {
      at[i] = static_cast<std::uint8_t>(value >> (8 * i));
    }
    return mjc::hal::FlashResult::kOk;
  }
  mjc::hal::FlashResult DoRead(std::uint32_t page, std::uint32_t offset,
                               std::span<std::uint8_t> out) const override {
    if (page >= 2 || offset + out.size() > kPageSize) {
      return mjc::hal::FlashResult::kBadAddress;
    }
    std::memcpy(out.data(), bytes.data() + page * kPageSize + offset, out.size());
    return mjc::hal::FlashResult::kOk;
  }
  std::uint32_t DoPageCount() const override { return 2; }
};

int Identity(const Args& a) {
  if (a.positional.size() != 1) Usage("identity takes OUT.bin");
  BoardIdentity id;
  id.node = static_cast<std::uint8_t>(Number(a.One("--node"), 8));
  id.hardware_revision = static_cast<std::uint8_t>(Number(a.One("--revision"), 255));
  if (id.node < 1 || id.hardware_revision < 1) {
    Usage("--node is 1..8 and --revision 1..255");
  }
  PagesInMemory pages;
  IdentityStore store(&pages, 0, 1);
  const auto loaded = store.Save(id) == IdentityResult::kOk ? store.Load() : std::nullopt;
  if (!loaded || loaded->identity.node != id.node ||
      loaded->identity.hardware_revision != id.hardware_revision) {
    std::fprintf(stderr, "mjc-image: the identity record did not read back\n");
    return 2;
  }
  if (!WriteAll(a.positional[0], pages.bytes)) {
    std::fprintf(stderr, "mjc-image: cannot write %s: %s\n", a.positional[0].c_str(),
                 std::strerror(errno));
    return 2;
  }
  std::printf("mjc-image: %s: identity pages, node %u, hardware revision %u\n",
              a.positional[0].c_str(), id.node, id.hardware_revision);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) Usage("no command");
  const std::string command = argv[1];
  const Args args = Parse(argc, argv, 2);
  if (command == "pack") return Pack(args);
  if (command == "show") return Show(args);
  if (command == "identity") return Identity(args);
  Usage(("unknown command '" + command + "'").c_str());
}
