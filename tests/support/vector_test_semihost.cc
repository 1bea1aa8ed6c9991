// Bare-metal driver: runs every registered vector case on the Cortex-M4 under QEMU,
// prints a GoogleTest-like log over semihosting, closes with "N passed, N failed" and
// returns the number of failed cases as the exit status (capped at 100).
#include <cstdio>

#include "test_io.h"
#include "vector_test.h"

namespace {

void StdoutSink(const char* file, int line, const char* message) {
  std::printf("%s:%d: Failure\n  %s\n", file, line, message);
}

}  // namespace

int main() {
  mjc::test::InitOutput();
  int passed = 0;
  int failed = 0;
  for (const mjc::vt::Case* c = mjc::vt::FirstCase(); c != nullptr; c = c->next) {
    std::printf("[ RUN      ] %s.%s\n", c->suite, c->name);
    mjc::vt::Context context(&StdoutSink);
    c->body(context);
    if (context.failures() == 0) {
      ++passed;
      std::printf("[       OK ] %s.%s\n", c->suite, c->name);
    } else {
      ++failed;
      std::printf("[  FAILED  ] %s.%s\n", c->suite, c->name);
    }
  }
  std::printf("%d passed, %d failed\n", passed, failed);
  std::fflush(stdout);
  return failed > 100 ? 100 : failed;
}
