#include "mjc/host/trial_runner.h"

#include <chrono>

namespace mjc::host {

using namespace mjc::protocol;

BoardTrial RunBoardTrial(BoardClient& board, const TrialConfig& config,
                         const std::function<void(const BoardWindow&)>& progress,
                         double timeout_s) {
  BoardTrial out;
  std::string why;
  board.TakeWindows();
  if (!board.SendTrialConfig(config, &why)) {
    out.error = why;
    return out;
  }
  const auto outcome = board.Command(CommandCode::kStartTrial, 1000, &why);
  if (!outcome) {
    out.error = why;
    return out;
  }
  if (*outcome != CommandOutcomeCode::kAccepted) {
    out.error = "the board refused the trial (outcome " +
                std::to_string(static_cast<int>(*outcome)) + ")";
    return out;
  }
  const auto deadline =
      std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  bool running_seen = false;
  auto idle_since = std::chrono::steady_clock::time_point{};
  while (std::chrono::steady_clock::now() < deadline) {
    board.Poll(20);
    for (BoardWindow& w : board.TakeWindows()) {
      if (progress) progress(w);
      out.windows.push_back(w);
    }
    const BoardState state = board.status().state;
    if (state == BoardState::kFault) {
      out.error = "the board faulted (fault " +
                  std::to_string(static_cast<int>(board.status().fault)) + ")";
      return out;
    }
    if (state == BoardState::kRunning) running_seen = true;
    if (running_seen && state == BoardState::kIdle) {
      // The last window leaves the board shortly after it goes idle: keep listening.
      if (idle_since == std::chrono::steady_clock::time_point{})
        idle_since = std::chrono::steady_clock::now();
      if (std::chrono::steady_clock::now() - idle_since >
          std::chrono::milliseconds(300)) {
        out.completed = true;
        return out;
      }
    }
  }
  out.error = "the trial did not finish within " +
              std::to_string(static_cast<int>(timeout_s)) + " s";
  return out;
}

std::vector<BoardWindow> MiddleFlexions(const std::vector<BoardWindow>& windows,
                                        std::uint16_t repetitions) {
  const RepetitionRange keep = MiddleRepetitions(repetitions, 3);
  std::vector<BoardWindow> out;
  for (const BoardWindow& w : windows) {
    if (w.motion == Motion::kFlexion && keep.Contains(w.repetition)) out.push_back(w);
  }
  return out;
}

}  // namespace mjc::host
