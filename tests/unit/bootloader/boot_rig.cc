#include "boot_rig.h"

#include <algorithm>

#include "mjc/protocol/little_endian.h"

namespace mjc::boot::test {

std::vector<std::uint8_t> MakeImage(std::size_t bytes, std::uint32_t seed) {
  std::vector<std::uint8_t> image(bytes);
  std::mt19937 rng(seed);
  for (auto& b : image) b = static_cast<std::uint8_t>(rng());
  protocol::PutLe(&image[0], 0x10000800u, 4);  // the interrupt stack's top in CCM
  // A Thumb reset handler inside the image.
  const std::uint32_t entry = bytes > 0x1DA ? 0x1D9u : 9u;
  protocol::PutLe(&image[4], kG474Layout.ImageAddress() + entry, 4);
  return image;
}

std::vector<std::uint8_t> MakeFile(std::span<const std::uint8_t> image,
                                   std::uint16_t board_type, std::uint8_t hw_min,
                                   std::uint8_t hw_max) {
  ImageHeader h;
  h.board_type = board_type;
  h.hardware_min = hw_min;
  h.hardware_max = hw_max;
  h.load_address = kG474Layout.ImageAddress();
  h.commit = 0x1958BA84u;
  h.commit_time_unix = 1795486377u;
  const std::string d = "test-image";
  std::copy(d.begin(), d.end(), h.describe.begin());
  return PackImage(image, h);
}

void Install(hal::Flash& flash, std::span<const std::uint8_t> file,
             const BootLayout& layout) {
  const std::uint32_t page_bytes = layout.PageBytes();
  for (std::uint32_t at = 0; at < file.size(); at += page_bytes) {
    (void)flash.ErasePage(layout.app_first_page + at / page_bytes);
  }
  for (std::uint32_t at = 0; at + 8 <= file.size(); at += 8) {
    const std::uint64_t v = protocol::GetLe(&file[at], 8);
    if (v == ~std::uint64_t{0}) continue;  // erased already
    (void)flash.ProgramDoubleWord(layout.app_first_page + at / page_bytes,
                                  at % page_bytes, v);
  }
}

std::vector<std::uint8_t> RegionBytes(hal::Flash& flash, std::size_t n,
                                      const BootLayout& layout) {
  std::vector<std::uint8_t> out(n);
  const std::uint32_t page_bytes = layout.PageBytes();
  for (std::uint32_t at = 0; at < n;) {
    const std::uint32_t in_page = at % page_bytes;
    const std::uint32_t k =
        std::min<std::uint32_t>(static_cast<std::uint32_t>(n) - at, page_bytes - in_page);
    (void)flash.Read(layout.app_first_page + at / page_bytes, in_page,
                     std::span<std::uint8_t>(out).subspan(at, k));
    at += k;
  }
  return out;
}

BootloaderConfig TestConfig() {
  BootloaderConfig c;
  c.layout = kG474Layout;
  c.board_type = kBoardType;
  c.hardware_revision = kHardware;
  c.node = kNode;
  c.build = 0xB0071234u;
  c.instance = 0x5A5A;
  c.reset_cause = protocol::ResetCause::kPowerOn;
  return c;
}

std::vector<protocol::CanFrame> IsoTpSegments(std::uint32_t id,
                                              std::span<const std::uint8_t> payload) {
  std::vector<protocol::CanFrame> frames;
  const auto frame = [&](std::initializer_list<std::uint8_t> pci, std::size_t from,
                         std::size_t n) {
    protocol::CanFrame f;
    f.id = id;
    f.length = 8;
    f.data.fill(0xCC);
    std::size_t k = 0;
    for (std::uint8_t b : pci) f.data[k++] = b;
    for (std::size_t i = 0; i < n; ++i) f.data[k + i] = payload[from + i];
    frames.push_back(f);
  };
  if (payload.size() <= 7) {
    frame({static_cast<std::uint8_t>(payload.size())}, 0, payload.size());
    return frames;
  }
  frame({static_cast<std::uint8_t>(0x10 | (payload.size() >> 8)),
         static_cast<std::uint8_t>(payload.size() & 0xFF)},
        0, 6);
  std::uint8_t seq = 1;
  for (std::size_t at = 6; at < payload.size(); at += 7) {
    frame({static_cast<std::uint8_t>(0x20 | seq)}, at,
          std::min<std::size_t>(7, payload.size() - at));
    seq = static_cast<std::uint8_t>((seq + 1) & 0x0F);
  }
  return frames;
}

std::vector<std::uint8_t> BeginRequest(std::span<const std::uint8_t> file,
                                       std::uint8_t sequence) {
  std::vector<std::uint8_t> r = {static_cast<std::uint8_t>(protocol::BootRequest::kBegin),
                                 sequence, 0, 0};
  r.insert(r.end(), file.begin(), file.begin() + kHeaderSize);
  return r;
}

std::vector<std::uint8_t> ChunkRequest(std::uint32_t offset,
                                       std::span<const std::uint8_t> data,
                                       std::uint8_t sequence) {
  std::vector<std::uint8_t> r(kChunkDataOffset, 0);
  r[0] = static_cast<std::uint8_t>(protocol::BootRequest::kChunk);
  r[1] = sequence;
  protocol::PutLe(&r[4], offset, 4);
  r.insert(r.end(), data.begin(), data.end());
  return r;
}

void Board::SendIsoTp(std::span<const std::uint8_t> payload) {
  const std::uint32_t id = protocol::MakeId(
      static_cast<std::uint8_t>(protocol::Function::kBootIsoTpToBoard), kNode);
  for (const auto& f : IsoTpSegments(id, payload)) Send(f);
}

std::optional<protocol::BootResult> Board::LastResult() {
  const auto results = Take<protocol::BootResult>();
  if (results.empty()) return std::nullopt;
  return results.back();
}

std::optional<protocol::BootResult> HostUpdate::AwaitResult(Board& board, int patience) {
  for (int i = 0; i < patience; ++i) {
    (void)board.Step();
    if (auto r = board.LastResult()) {
      results.push_back(*r);
      return r;
    }
  }
  return std::nullopt;
}

std::optional<protocol::BootResult> HostUpdate::Request(
    Board& board, std::span<const std::uint8_t> payload, int patience) {
  board.can.from_board.clear();
  board.SendIsoTp(payload);
  return AwaitResult(board, patience);
}

std::optional<protocol::BootResult> HostUpdate::Command(Board& board,
                                                        protocol::BootRequest request,
                                                        int patience) {
  board.can.from_board.clear();
  protocol::BootCommand c;
  c.request = request;
  c.sequence = 7;
  board.Send(protocol::Encode(c, kNode));
  return AwaitResult(board, patience);
}

bool HostUpdate::Run(Board& board, std::span<const std::uint8_t> file,
                     std::size_t chunk_bytes) {
  using protocol::BootError;
  const auto ok = [](const std::optional<protocol::BootResult>& r) {
    return r && r->error == BootError::kNone;
  };
  if (!ok(Request(board, BeginRequest(file)))) return false;
  const auto image = file.subspan(kHeaderArea);
  for (std::size_t at = 0; at < image.size(); at += chunk_bytes) {
    const std::size_t n = std::min(chunk_bytes, image.size() - at);
    const auto r =
        Request(board, ChunkRequest(static_cast<std::uint32_t>(at), image.subspan(at, n),
                                    static_cast<std::uint8_t>(at / chunk_bytes)));
    if (!ok(r) || r->next_offset != at + n) return false;
  }
  if (!ok(Command(board, protocol::BootRequest::kCommit))) return false;
  return ok(Command(board, protocol::BootRequest::kBoot));
}

}  // namespace mjc::boot::test
