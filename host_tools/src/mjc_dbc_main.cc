// mjc-dbc: prints the protocol's DBC file (host_tools/maestro_jc.dbc is its output).
#include <cstdio>

#include "mjc/host/dbc.h"

int main(int argc, char** argv) {
  if (argc != 1) {
    std::fprintf(stderr, "usage: %s > maestro_jc.dbc   (takes no arguments)\n", argv[0]);
    return 2;
  }
  std::fputs(mjc::host::GenerateDbc().c_str(), stdout);
  return 0;
}
