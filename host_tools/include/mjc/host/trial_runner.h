// Runs one sine trial on a board over the bus: configure, start, follow it until the
// board is idle again, and collect its window summaries.
#pragma once

#include <chrono>
#include <functional>
#include <string>
#include <vector>

#include "mjc/host/board_client.h"

namespace mjc::host {

// How a trial ended.
enum class TrialEnd : std::uint8_t {
  kCompleted = 0,
  kLinkFailed = 1,   // the host could not send or receive
  kNoAnswer = 2,     // the board did not answer the start, or did not finish in time
  kRefused = 3,      // the board refused the start
  kFaulted = 4,      // the board faulted during the trial
  kInterrupted = 5,  // the client's interrupt flag was raised (a signal)
  kStopped = 6,      // the board went idle before the trial's end (another tool's stop)
  kAmbiguous = 7,    // two boards answer with the node's id (BoardClient::ambiguous)
  kWrongConfig = 8,  // the board runs another configuration or session's motion than
                     // the one started (nothing of it recorded; the caller stops it)
};

struct BoardTrial {
  std::vector<BoardWindow> windows;
  TrialEnd end = TrialEnd::kNoAnswer;
  bool completed = false;  // end == kCompleted
  std::string error;       // why it did not complete
};

// How long the trial runs on the board: its repetitions and the rests before and
// after them.
std::chrono::milliseconds TrialBoardTime(const protocol::TrialConfig& config);

// `progress` gets each completed window. The wait follows the board's pace (see
// Patience): at most twice the trial's own length in board time, and the board may not
// fall silent for longer than the default silence.
BoardTrial RunBoardTrial(BoardClient& board, const protocol::TrialConfig& config,
                         const std::function<void(const BoardWindow&)>& progress);

}  // namespace mjc::host
