// The trial runner's arithmetic (mjc/host/trial_runner.h): how long a trial runs on
// the board, from its configuration by hand. (The run itself over a bus against the
// simulated board: tests/sim/bus_trial_test.cc and the kernel layer; which windows are
// the paper's analysed flexions: report_test.cc.)
#include "mjc/host/trial_runner.h"

#include <gtest/gtest.h>

#include <chrono>

namespace mjc::host {
namespace {

using namespace std::chrono_literals;
using protocol::TrialConfig;

TEST(TrialBoardTime, RepetitionsOverFrequencyPlusBothRests) {
  TrialConfig c;
  c.frequency_mHz = 500;  // 0.5 Hz: 2 s per repetition
  c.repetitions = 5;
  c.rest_100ms = 15;  // 1.5 s before and after
  EXPECT_EQ(TrialBoardTime(c), 13000ms);
  c.frequency_mHz = 2000;  // 0.5 s per repetition
  c.repetitions = 3;
  c.rest_100ms = 2;
  EXPECT_EQ(TrialBoardTime(c), 1900ms);
  c.frequency_mHz = 3000;  // 1/3 s per repetition: 333.33 ms, rounded to the nearest
  c.repetitions = 1;
  c.rest_100ms = 0;
  EXPECT_EQ(TrialBoardTime(c), 333ms);
  c.frequency_mHz = 1500;  // 2/3 s: 666.67 ms
  EXPECT_EQ(TrialBoardTime(c), 667ms);
}

}  // namespace
}  // namespace mjc::host
