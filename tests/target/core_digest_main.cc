// Prints the core digest (see core_digest.h) as "core_digest: <16 hex digits>".
#include <cstdio>

#include "core_digest.h"
#include "test_io.h"

// 200,000 steps: about 6 million core operations, a few seconds under QEMU.
constexpr std::uint32_t kSteps = 200000;

int main() {
  mjc::test::InitOutput();
  std::printf("core_digest: %016llx (%lu steps)\n",
              static_cast<unsigned long long>(mjc::test::CoreDigest(kSteps)),
              static_cast<unsigned long>(kSteps));
  std::fflush(stdout);
  return 0;
}
