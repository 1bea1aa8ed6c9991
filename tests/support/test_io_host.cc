#include "test_io.h"

namespace mjc::test {

void InitOutput() {}

}  // namespace mjc::test
