// Runs one sine trial on a board over the bus: configure, start, follow it until the
// board is idle again, and collect its window summaries.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "mjc/host/board_client.h"

namespace mjc::host {

struct BoardTrial {
  std::vector<BoardWindow> windows;
  bool completed = false;
  std::string error;  // why it did not complete (refused, silent node, fault, timeout)
};

// `progress` gets a line per completed window. timeout_s bounds the wall time.
BoardTrial RunBoardTrial(BoardClient& board, const protocol::TrialConfig& config,
                         const std::function<void(const BoardWindow&)>& progress,
                         double timeout_s);

// The paper's analysed flexions: the middle three of `repetitions`.
std::vector<BoardWindow> MiddleFlexions(const std::vector<BoardWindow>& windows,
                                        std::uint16_t repetitions);

}  // namespace mjc::host
