// The DBC against the codec: the committed maestro_jc.dbc is what mjc-dbc generates
// now, and an independent decoder (Debian's python3-canmatrix, driven by
// canmatrix_decode.py under /usr/bin/python3) reads every signal of frames our encoder
// wrote with the raw and physical values we put in.
#include "mjc/host/dbc.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include "mjc/protocol/codec.h"
#include "vector_test.h"

namespace {

using namespace mjc;
using namespace mjc::protocol;
namespace fs = std::filesystem;

std::string ReadFile(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST(Dbc, CommittedFileIsTheGeneratedOne) {
  const std::string committed =
      ReadFile(fs::path(MJC_SOURCE_DIR) / "host_tools/maestro_jc.dbc");
  ASSERT_FALSE(committed.empty()) << "host_tools/maestro_jc.dbc missing";
  EXPECT_EQ(committed, host::GenerateDbc())
      << "regenerate: build/host/host_tools/mjc-dbc > host_tools/maestro_jc.dbc";
}

struct Expected {
  std::string name;
  bool fd = false;
  std::vector<std::tuple<std::string, std::int64_t, double>>
      signals;  // name, raw, factor
};

template <class M>
void AddFrames(vt::Rng& rng, std::ofstream& frames, std::vector<Expected>& expected) {
  for (int i = 0; i < 25; ++i) {
    // Random payload bits, decoded by our codec: only legal frames are kept, so the
    // values span every field's whole legal range.
    CanFrame f;
    const auto node = static_cast<std::uint8_t>(1 + rng.Next() % 8u);
    f.id = IdOf<M>(node);
    f.length = Message<M>::kLength;
    f.fd = Message<M>::kFd;
    for (auto& b : f.data) b = static_cast<std::uint8_t>(rng.Next());
    M m;
    if (Decode(f, &m) != DecodeError::kOk) continue;
    const CanFrame clean = Encode(m, node);
    char head[16];
    std::snprintf(head, sizeof head, "%03X ", clean.id);
    frames << head;
    for (int k = 0; k < clean.length; ++k) {
      char byte[4];
      std::snprintf(byte, sizeof byte, "%02X", clean.data[static_cast<std::size_t>(k)]);
      frames << byte;
    }
    frames << '\n';
    Expected e;
    e.fd = Message<M>::kFd;
    e.name = std::string(Message<M>::kName) +
             (Message<M>::kBroadcast ? "" : "_J" + std::to_string(node));
    std::apply(
        [&](const auto&... s) {
          ((e.signals.emplace_back(
               s.name, std::decay_t<decltype(s)>::Wire::ToRaw(s.Get(m)), s.factor())),
           ...);
        },
        Message<M>::kSignals);
    expected.push_back(std::move(e));
  }
}

TEST(Dbc, IndependentDecoderReadsEverySignalWeEncode) {
  ASSERT_TRUE(fs::exists("/usr/bin/python3"))
      << "Debian's python3 is needed (scripts/setup)";
  // Its own folder per process: test runs of several build trees may overlap.
  const fs::path dir =
      fs::temp_directory_path() / ("mjc_dbc_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  std::ofstream(dir / "maestro_jc.dbc") << host::GenerateDbc();
  std::vector<Expected> expected;
  {
    std::ofstream frames(dir / "frames.txt");
    vt::Rng rng(601);
    std::apply([&](auto... m) { (AddFrames<decltype(m)>(rng, frames, expected), ...); },
               AllMessages{});
  }
  ASSERT_GT(expected.size(), 200u);
  const std::string command = "/usr/bin/python3 '" MJC_SOURCE_DIR
                              "/tests/unit/protocol/canmatrix_decode.py' '" +
                              (dir / "maestro_jc.dbc").string() + "' '" +
                              (dir / "frames.txt").string() + "' 2>&1";
  FILE* pipe = popen(command.c_str(), "r");
  ASSERT_NE(pipe, nullptr);
  std::string out;
  char buffer[4096];
  while (std::fgets(buffer, sizeof buffer, pipe) != nullptr) out += buffer;
  const int status = pclose(pipe);
  fs::remove_all(dir);
  ASSERT_EQ(status, 0) << "canmatrix failed (python3-canmatrix installed?):\n" << out;

  std::istringstream lines(out);
  std::string line;
  std::size_t index = 0, signals = 0;
  while (std::getline(lines, line)) {
    if (line.empty() || line[0] != '{') continue;  // canmatrix's own notices
    ASSERT_LT(index, expected.size());
    const auto j = nlohmann::json::parse(line);
    ASSERT_FALSE(j.contains("error")) << j.dump();
    const Expected& e = expected[index++];
    EXPECT_EQ(j["name"].get<std::string>(), e.name);
    EXPECT_EQ(j["fd"].get<bool>(), e.fd) << e.name;
    for (const auto& [name, raw, factor] : e.signals) {
      ASSERT_TRUE(j["raw"].contains(name)) << e.name << "." << name;
      EXPECT_EQ(j["raw"][name].get<std::int64_t>(), raw) << e.name << "." << name;
      const double phys = std::stod(j["phys"][name].get<std::string>());
      const double want = static_cast<double>(raw) * factor;
      EXPECT_NEAR(phys, want, 1e-12 * std::fabs(want) + 1e-15) << e.name << "." << name;
      ++signals;
    }
  }
  EXPECT_EQ(index, expected.size());
  std::printf("[ canmatrix] %zu frames, %zu signals decoded identically\n", index,
              signals);
}

}  // namespace
