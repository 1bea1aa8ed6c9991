// The image header: its layout byte for byte (the table in image_header.h), its CRCs
// against zlib's (an implementation we did not write), every way a header or an image
// file is refused, and the packer (library and program).
#include "mjc/boot/image_header.h"

#include <gtest/gtest.h>
#include <zlib.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

#include "image_file.h"
#include "mjc/protocol/little_endian.h"

namespace {

using namespace mjc::boot;
using mjc::protocol::GetLe;

std::uint32_t ZlibCrc(const std::uint8_t* p, std::size_t n) {
  return static_cast<std::uint32_t>(crc32(crc32(0L, Z_NULL, 0), p, static_cast<uInt>(n)));
}

ImageHeader Sample() {
  ImageHeader h;
  h.board_type = 1;
  h.hardware_min = 2;
  h.hardware_max = 5;
  h.length = 4096;
  h.image_crc = 0x12345678u;
  h.load_address = 0x08004200u;
  h.commit = 0x1958BA84u;
  h.dirty = true;
  h.commit_time_unix = 1795486377u;
  const std::string d = "v0.1-3-g1958ba84-dirty";
  std::copy(d.begin(), d.end(), h.describe.begin());
  return h;
}

TEST(ImageHeader, LayoutIsTheDocumentedTable) {
  const HeaderBytes b = EncodeHeader(Sample());
  EXPECT_EQ(GetLe(&b[0], 4), 0x49434A4Du);
  EXPECT_EQ(b[0], 'M');
  EXPECT_EQ(b[3], 'I');
  EXPECT_EQ(GetLe(&b[4], 2), 1u);
  EXPECT_EQ(GetLe(&b[6], 2), 128u);
  EXPECT_EQ(GetLe(&b[8], 2), 1u);
  EXPECT_EQ(b[10], 2);
  EXPECT_EQ(b[11], 5);
  EXPECT_EQ(GetLe(&b[12], 4), 4096u);
  EXPECT_EQ(GetLe(&b[16], 4), 0x12345678u);
  EXPECT_EQ(GetLe(&b[20], 4), 0x08004200u);
  EXPECT_EQ(GetLe(&b[24], 4), 0x1958BA84u);
  EXPECT_EQ(GetLe(&b[28], 4), 1u);  // dirty
  EXPECT_EQ(GetLe(&b[32], 8), 1795486377u);
  EXPECT_EQ(std::string(reinterpret_cast<const char*>(&b[40])), "v0.1-3-g1958ba84-dirty");
  for (std::size_t i = 40 + 22; i < 120; ++i) EXPECT_EQ(b[i], 0) << i;
  EXPECT_EQ(GetLe(&b[120], 4), ZlibCrc(b.data(), 120));
  EXPECT_EQ(GetLe(&b[124], 4), 0xB007C0DEu);
}

TEST(ImageHeader, RoundTrips) {
  const ImageHeader in = Sample();
  ImageHeader out;
  ASSERT_EQ(DecodeHeader(EncodeHeader(in), &out), ImageCheck::kValid);
  EXPECT_EQ(out.board_type, in.board_type);
  EXPECT_EQ(out.hardware_min, in.hardware_min);
  EXPECT_EQ(out.hardware_max, in.hardware_max);
  EXPECT_EQ(out.length, in.length);
  EXPECT_EQ(out.image_crc, in.image_crc);
  EXPECT_EQ(out.load_address, in.load_address);
  EXPECT_EQ(out.commit, in.commit);
  EXPECT_EQ(out.dirty, in.dirty);
  EXPECT_EQ(out.describe_cut, in.describe_cut);
  EXPECT_EQ(out.commit_time_unix, in.commit_time_unix);
  EXPECT_EQ(out.describe, in.describe);
}

TEST(ImageHeader, ErasedOrBlankIsNoImage) {
  HeaderBytes b;
  ImageHeader out;
  b.fill(0xFF);
  EXPECT_EQ(DecodeHeader(b, &out), ImageCheck::kNoImage);
  b.fill(0x00);
  EXPECT_EQ(DecodeHeader(b, &out), ImageCheck::kNoImage);
}

TEST(ImageHeader, EveryDamagedByteIsRefused) {
  const HeaderBytes good = EncodeHeader(Sample());
  for (std::size_t i = 0; i < kHeaderSize; ++i) {
    for (int flip : {0x01, 0x80, 0xFF}) {
      HeaderBytes b = good;
      b[i] = static_cast<std::uint8_t>(b[i] ^ flip);
      ImageHeader out;
      out.length = 777;
      const ImageCheck c = DecodeHeader(b, &out);
      EXPECT_TRUE(c == ImageCheck::kBadHeader || (i < 4 && c == ImageCheck::kNoImage))
          << "byte " << i << " flip " << flip;
      EXPECT_EQ(out.length, 777u) << "a refused header writes nothing";
    }
  }
}

// A header whose CRC is right but whose content breaks a rule of the format.
HeaderBytes Resealed(HeaderBytes b) {
  mjc::protocol::PutLe(&b[120], ZlibCrc(b.data(), 120), 4);
  return b;
}

TEST(ImageHeader, RuleBreakersWithAValidCrcAreRefused) {
  ImageHeader out;
  HeaderBytes b = EncodeHeader(Sample());
  b[4] = 2;  // a format this bootloader does not know
  EXPECT_EQ(DecodeHeader(Resealed(b), &out), ImageCheck::kBadHeader);
  b = EncodeHeader(Sample());
  b[6] = 120;  // another header size
  EXPECT_EQ(DecodeHeader(Resealed(b), &out), ImageCheck::kBadHeader);
  b = EncodeHeader(Sample());
  b[28] |= 0x04;  // an unknown flag
  EXPECT_EQ(DecodeHeader(Resealed(b), &out), ImageCheck::kBadHeader);
  b = EncodeHeader(Sample());
  b[119] = 'x';  // a describe without its terminating NUL
  EXPECT_EQ(DecodeHeader(Resealed(b), &out), ImageCheck::kBadHeader);
  b = EncodeHeader(Sample());
  b[124] ^= 1;  // commit mark
  EXPECT_EQ(DecodeHeader(Resealed(b), &out), ImageCheck::kBadHeader);
  EXPECT_EQ(DecodeHeader(Resealed(EncodeHeader(Sample())), &out), ImageCheck::kValid);
}

TEST(ImageHeader, DescribeKeepsAtMost79Characters) {
  ImageHeader h = Sample();
  h.describe.fill('a');  // no NUL at all
  ImageHeader out;
  ASSERT_EQ(DecodeHeader(EncodeHeader(h), &out), ImageCheck::kValid);
  EXPECT_EQ(DescribeOf(out), std::string(79, 'a'));
}

TEST(ImageHeader, CheckedAgainstTheBoard) {
  const ImageTarget t{.board_type = 1,
                      .hardware_revision = 3,
                      .load_address = 0x08004200u,
                      .max_length = 245248};
  ImageHeader h = Sample();
  EXPECT_EQ(CheckHeaderFor(h, t), ImageCheck::kValid);
  h.board_type = 2;
  EXPECT_EQ(CheckHeaderFor(h, t), ImageCheck::kWrongBoard);
  h = Sample();
  for (int rev : {0, 1, 6, 255}) {
    ImageTarget other = t;
    other.hardware_revision = static_cast<std::uint8_t>(rev);
    EXPECT_EQ(CheckHeaderFor(h, other), ImageCheck::kWrongHardware) << rev;
  }
  for (int rev : {2, 5}) {
    ImageTarget other = t;
    other.hardware_revision = static_cast<std::uint8_t>(rev);
    EXPECT_EQ(CheckHeaderFor(h, other), ImageCheck::kValid) << rev;
  }
  for (std::uint32_t length : {0u, 4u, 4097u, 245256u}) {
    h.length = length;
    EXPECT_EQ(CheckHeaderFor(h, t), ImageCheck::kBadLength) << length;
  }
  h.length = 245248;
  EXPECT_EQ(CheckHeaderFor(h, t), ImageCheck::kValid);
  h.load_address = 0x08004000u;
  EXPECT_EQ(CheckHeaderFor(h, t), ImageCheck::kBadLoadAddress);
}

std::vector<std::uint8_t> SomeImage(std::size_t n) {
  std::vector<std::uint8_t> image(n);
  for (std::size_t i = 0; i < n; ++i) image[i] = static_cast<std::uint8_t>(i * 7 + 3);
  return image;
}

TEST(ImageFile, PackPadsAndChecks) {
  const std::vector<std::uint8_t> image = SomeImage(1003);
  const std::vector<std::uint8_t> file = PackImage(image, Sample());
  ASSERT_EQ(file.size(), kHeaderArea + 1008);
  for (std::size_t i = kHeaderSize; i < kHeaderArea; ++i) EXPECT_EQ(file[i], 0xFF) << i;
  for (std::size_t i = 1003; i < 1008; ++i) EXPECT_EQ(file[kHeaderArea + i], 0xFF);
  EXPECT_TRUE(std::equal(image.begin(), image.end(), file.begin() + kHeaderArea));
  ImageHeader h;
  ASSERT_EQ(CheckImageFile(file, &h), ImageCheck::kValid);
  EXPECT_EQ(h.length, 1008u);
  EXPECT_EQ(h.image_crc, ZlibCrc(file.data() + kHeaderArea, 1008));
}

TEST(ImageFile, TruncatedCorruptedOrPaddedFilesAreRefused) {
  const std::vector<std::uint8_t> file = PackImage(SomeImage(2048), Sample());
  ImageHeader h;
  std::vector<std::uint8_t> f = file;
  f.resize(f.size() - 8);
  EXPECT_EQ(CheckImageFile(f, &h), ImageCheck::kBadLength);
  f = file;
  f.push_back(0xFF);
  EXPECT_EQ(CheckImageFile(f, &h), ImageCheck::kBadLength);
  f = file;
  f.resize(300);
  EXPECT_EQ(CheckImageFile(f, &h), ImageCheck::kBadLength);
  f.resize(100);
  EXPECT_EQ(CheckImageFile(f, &h), ImageCheck::kNoImage);
  for (std::size_t at :
       {std::size_t{0}, std::size_t{1000}, file.size() - 1 - kHeaderArea}) {
    f = file;
    f[kHeaderArea + at] ^= 0x10;
    EXPECT_EQ(CheckImageFile(f, &h), ImageCheck::kImageCrc) << at;
  }
}

std::vector<std::uint8_t> ReadBytes(const std::string& path) {
  std::vector<std::uint8_t> bytes;
  EXPECT_TRUE(ReadFileBytes(path, &bytes)) << path;
  return bytes;
}

int Shell(const std::string& command) {
  const int status = std::system((command + " > /dev/null").c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

// The program the build runs: pack, show, and a corrupted copy.
TEST(MjcImage, PacksShowsAndRefuses) {
  const std::string dir = ::testing::TempDir();
  const std::string raw = dir + "/mjc_image_raw.bin", out = dir + "/mjc_image_app.bin",
                    bad = dir + "/mjc_image_bad.bin";
  // A vector table for 0x08004200: stack pointer, then a Thumb reset handler inside.
  std::vector<std::uint8_t> image = SomeImage(600);
  mjc::protocol::PutLe(&image[0], 0x10000800u, 4);
  mjc::protocol::PutLe(&image[4], 0x08004200u + 0x101u, 4);
  {
    std::ofstream f(raw, std::ios::binary);
    f.write(reinterpret_cast<const char*>(image.data()),
            static_cast<std::streamsize>(image.size()));
  }
  const std::string tool = MJC_IMAGE_TOOL;
  const std::string args =
      " --board-type 1 --hardware 1 1 --load-address 0x08004200 --commit 1958ba84"
      " --dirty 0 --commit-time 1795486377 --describe v1-2-g1958ba84";
  ASSERT_EQ(Shell(tool + " pack " + raw + " " + out + args), 0);
  ImageFile file;
  std::string why;
  ASSERT_TRUE(ReadImageFile(out, &file, &why)) << why;
  EXPECT_EQ(file.check, ImageCheck::kValid);
  EXPECT_EQ(file.header.commit, 0x1958BA84u);
  EXPECT_EQ(DescribeOf(file.header), "v1-2-g1958ba84");
  EXPECT_EQ(file.bytes, PackImage(image, file.header)) << "the program is the library";
  const std::string target =
      " --board-type 1 --hardware-revision 1 --load-address 0x08004200 --max-length "
      "245248";
  EXPECT_EQ(Shell(tool + " show " + out + target), 0);
  EXPECT_EQ(Shell(tool + " show " + out +
                  " --board-type 2 --hardware-revision 1 "
                  "--load-address 0x08004200 --max-length 245248"),
            1);
  ASSERT_EQ(Shell(tool + " pack " + raw + " " + bad + args + " --flip-byte 300"), 0);
  EXPECT_EQ(Shell(tool + " show " + bad), 1);
  ASSERT_TRUE(ReadImageFile(bad, &file, &why));
  EXPECT_EQ(file.check, ImageCheck::kImageCrc);
  // A reset vector outside the image (linked for another address) is refused.
  EXPECT_EQ(Shell(tool + " pack " + raw + " " + bad +
                  " --board-type 1 --hardware 1 1 --load-address 0x08010000 --commit 0"
                  " --dirty 0 --commit-time 0 --describe x"),
            1);
  EXPECT_EQ(ReadBytes(out).size(), kHeaderArea + 600);
}

// The identity pages for a first flash through the debug connector: the layout of
// identity_store.h's table, read here byte by byte, with zlib's CRC-32; page B erased;
// a node outside 1..8 refused with nothing written.
TEST(MjcImage, WritesIdentityPages) {
  const std::string path = ::testing::TempDir() + "/mjc_image_identity.bin";
  std::remove(path.c_str());
  const std::string tool = MJC_IMAGE_TOOL;
  ASSERT_EQ(Shell(tool + " identity " + path + " --node 5 --revision 2"), 0);
  const std::vector<std::uint8_t> pages = ReadBytes(path);
  ASSERT_EQ(pages.size(), 4096u);
  EXPECT_EQ(GetLe(&pages[0], 4), 0x44494A4Du);  // 'MJID'
  EXPECT_EQ(GetLe(&pages[4], 2), 1u);           // record version
  EXPECT_EQ(GetLe(&pages[6], 2), 8u);           // payload length
  EXPECT_EQ(pages[16], 5);                      // node id
  EXPECT_EQ(pages[17], 2);                      // hardware revision
  EXPECT_EQ(GetLe(&pages[24], 4), ZlibCrc(pages.data(), 24));
  EXPECT_EQ(GetLe(&pages[28], 4), 0xC0DE1D1Du);  // commit mark
  for (std::size_t i = 32; i < pages.size(); ++i) {
    ASSERT_EQ(pages[i], 0xFF) << "byte " << i << " must be erased";
  }
  std::remove(path.c_str());
  EXPECT_EQ(Shell(tool + " identity " + path + " --node 9 --revision 1 2>/dev/null"), 2);
  EXPECT_EQ(Shell(tool + " identity " + path + " --node 1 --revision 0 2>/dev/null"), 2);
  std::ifstream absent(path);
  EXPECT_FALSE(absent.good()) << "a refused identity writes no file";
}

}  // namespace
