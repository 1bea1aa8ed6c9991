// The kernel layer's C++ self-tests (run inside the VM by scripts/kernel-vm): one
// "PASS what" or "FAIL what" line per check, figures as "name: value unit" lines, and
// the closing "N passed, N failed" whose exit status is the verdict.
#pragma once

#include <cstdio>
#include <string>

namespace mjc::kernel_test {

class SelfCheck {
 public:
  void operator()(bool ok, const std::string& what) {
    std::printf("%s %s\n", ok ? "PASS" : "FAIL", what.c_str());
    ++(ok ? passed_ : failed_);
  }
  // Prints the closing line; the exit status: 0 when every check passed.
  int Finish() const {
    std::printf("%d passed, %d failed\n", passed_, failed_);
    return failed_ == 0 ? 0 : 1;
  }

 private:
  int passed_ = 0;
  int failed_ = 0;
};

}  // namespace mjc::kernel_test
