// mjc-dbc: prints the protocol's DBC file (host_tools/maestro_jc.dbc is its output).
#include <cerrno>
#include <cstdio>
#include <cstring>

#include "mjc/host/dbc.h"

int main(int argc, char** argv) {
  if (argc != 1) {
    std::fprintf(stderr, "usage: %s > maestro_jc.dbc   (takes no arguments)\n", argv[0]);
    return 2;
  }
  // Redirected into maestro_jc.dbc: a short write (full disk) must not pass for a DBC.
  if (std::fputs(mjc::host::GenerateDbc().c_str(), stdout) < 0 ||
      std::fflush(stdout) != 0) {
    std::fprintf(stderr, "mjc-dbc: error writing stdout: %s\n", std::strerror(errno));
    return 1;
  }
  return 0;
}
