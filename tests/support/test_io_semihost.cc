#include "test_io.h"

extern "C" void initialise_monitor_handles();

namespace mjc::test {

void InitOutput() { initialise_monitor_handles(); }

}  // namespace mjc::test
