// The trial runner's arithmetic (mjc/host/trial_runner.h): how long a trial runs on
// the board, from its configuration by hand, and which windows are the paper's
// analysed flexions. (The run itself over a bus against the simulated board:
// tests/sim/bus_trial_test.cc and the kernel layer.)
#include "mjc/host/trial_runner.h"

#include <gtest/gtest.h>

#include <chrono>
#include <vector>

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

std::vector<BoardWindow> Windows(int repetitions) {
  std::vector<BoardWindow> w;
  for (int r = 0; r < repetitions; ++r) {
    for (const Motion m : {Motion::kFlexion, Motion::kExtension}) {
      BoardWindow b;
      b.motion = m;
      b.repetition = static_cast<std::uint16_t>(r);
      w.push_back(b);
    }
  }
  return w;
}

std::vector<int> Repetitions(const std::vector<BoardWindow>& windows) {
  std::vector<int> r;
  for (const BoardWindow& w : windows) {
    EXPECT_EQ(w.motion, Motion::kFlexion);
    r.push_back(w.repetition);
  }
  return r;
}

TEST(MiddleFlexions, TheMiddleThreeFlexions) {
  // Repetitions count from 0: of 0..4 the middle three are 1, 2, 3; of 0..5 (even:
  // one more after than before) 1, 2, 3; of 0..6, 2, 3, 4.
  EXPECT_EQ(Repetitions(MiddleFlexions(Windows(5), 5)), (std::vector<int>{1, 2, 3}));
  EXPECT_EQ(Repetitions(MiddleFlexions(Windows(6), 6)), (std::vector<int>{1, 2, 3}));
  EXPECT_EQ(Repetitions(MiddleFlexions(Windows(7), 7)), (std::vector<int>{2, 3, 4}));
}

TEST(MiddleFlexions, AllOfThreeOrFewerAndNoneMissingInvented) {
  EXPECT_EQ(Repetitions(MiddleFlexions(Windows(3), 3)), (std::vector<int>{0, 1, 2}));
  EXPECT_EQ(Repetitions(MiddleFlexions(Windows(2), 2)), (std::vector<int>{0, 1}));
  // A window lost on the way: the analysis has what arrived, nothing made up.
  std::vector<BoardWindow> w = Windows(5);
  w.erase(w.begin() + 4);  // repetition 2's flexion
  EXPECT_EQ(Repetitions(MiddleFlexions(w, 5)), (std::vector<int>{1, 3}));
  EXPECT_TRUE(MiddleFlexions({}, 5).empty());
}

}  // namespace
}  // namespace mjc::host
