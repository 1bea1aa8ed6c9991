#include "mjc/host/trial_runner.h"

#include <chrono>

#include "mjc/host/describe.h"

namespace mjc::host {

using namespace mjc::protocol;

BoardTrial RunBoardTrial(BoardClient& board, const TrialConfig& config,
                         const std::function<void(const BoardWindow&)>& progress,
                         double timeout_s) {
  BoardTrial out;
  const auto fail = [&out](TrialEnd end, std::string why) {
    out.end = end;
    out.error = std::move(why);
    return out;
  };
  std::string why;
  board.TakeWindows();
  if (!board.Send(config, &why)) return fail(TrialEnd::kLinkFailed, why);
  const auto outcome = board.Command(CommandCode::kStartTrial, 1000, &why);
  if (!outcome) {
    return fail(board.link_failed() ? TrialEnd::kLinkFailed : TrialEnd::kNoAnswer, why);
  }
  if (*outcome != CommandOutcomeCode::kAccepted) {
    return fail(TrialEnd::kRefused,
                "the board refused the trial: " + std::string(OutcomeName(*outcome)));
  }
  const auto deadline =
      std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  bool running_seen = false;
  auto idle_since = std::chrono::steady_clock::time_point{};
  while (std::chrono::steady_clock::now() < deadline) {
    if (!board.Poll(20, &why)) return fail(TrialEnd::kLinkFailed, why);
    for (BoardWindow& w : board.TakeWindows()) {
      if (progress) progress(w);
      out.windows.push_back(w);
    }
    const BoardState state = board.status().state;
    if (state == BoardState::kFault) {
      return fail(TrialEnd::kFaulted,
                  "the board faulted: fault " + DescribeFault(board.status().fault));
    }
    if (state == BoardState::kRunning) running_seen = true;
    if (running_seen && state == BoardState::kIdle) {
      // The last window leaves the board shortly after it goes idle: keep listening.
      if (idle_since == std::chrono::steady_clock::time_point{})
        idle_since = std::chrono::steady_clock::now();
      if (std::chrono::steady_clock::now() - idle_since >
          std::chrono::milliseconds(300)) {
        out.end = TrialEnd::kCompleted;
        out.completed = true;
        return out;
      }
    }
  }
  return fail(TrialEnd::kNoAnswer, "the trial did not finish within " +
                                       std::to_string(static_cast<int>(timeout_s)) +
                                       " s");
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
