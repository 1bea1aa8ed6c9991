#include "mjc/host/trial_runner.h"

#include <chrono>

#include "mjc/host/describe.h"

namespace mjc::host {

using namespace mjc::protocol;

std::chrono::milliseconds TrialBoardTime(const TrialConfig& config) {
  const double frequency_hz = config.frequency_mHz / 1000.0;
  const double seconds = config.repetitions / frequency_hz + 2 * config.rest_100ms / 10.0;
  return std::chrono::milliseconds(static_cast<std::int64_t>(seconds * 1000.0 + 0.5));
}

BoardTrial RunBoardTrial(BoardClient& board, const TrialConfig& config,
                         const std::function<void(const BoardWindow&)>& progress) {
  BoardTrial out;
  const auto fail = [&out](TrialEnd end, std::string why) {
    out.end = end;
    out.error = std::move(why);
    return out;
  };
  std::string why;
  board.TakeWindows();
  const std::uint64_t broken_before = board.incomplete_windows();
  if (!board.Send(config, &why)) return fail(TrialEnd::kLinkFailed, why);
  const auto outcome = board.Command(CommandCode::kStartTrial, kStartAnswerMs, &why);
  if (!outcome) {
    if (board.interrupted()) return fail(TrialEnd::kInterrupted, why);
    if (board.ambiguous()) return fail(TrialEnd::kAmbiguous, why);
    return fail(board.link_failed() ? TrialEnd::kLinkFailed : TrialEnd::kNoAnswer, why);
  }
  if (*outcome != CommandOutcomeCode::kAccepted) {
    // Not idle: a latched fault is the usual reason, and it has a remedy to name.
    WaitEnd end{};
    const std::chrono::milliseconds second{1000};
    if (*outcome == CommandOutcomeCode::kRefusedNotIdle &&
        board.Await([&] { return board.status().heard; }, {second, second}, &end, &why) &&
        board.status().state == BoardState::kFault) {
      return fail(TrialEnd::kRefused, "the board refused the trial: it holds fault " +
                                          DescribeFault(board.status().fault) +
                                          "; clear it with mjc clear --node " +
                                          std::to_string(board.node()) +
                                          " once its cause is gone");
    }
    return fail(TrialEnd::kRefused,
                "the board refused the trial: " + std::string(OutcomeName(*outcome)));
  }
  // Followed at the board's pace: done when the board says it is idle again after
  // running. Its frames arrive in the order it sent them, and it sends a window's
  // frames before the heartbeat that reports the trial over, so every window is in by
  // then. Bounded by twice the trial's own length in the board's time, and by silence.
  bool running_seen = false;
  const auto finished = [&] {
    for (BoardWindow& w : board.TakeWindows()) {
      if (progress) progress(w);
      out.windows.push_back(w);
    }
    const BoardState state = board.status().state;
    if (state == BoardState::kRunning) running_seen = true;
    return state == BoardState::kFault || (running_seen && state == BoardState::kIdle);
  };
  const Patience patience{2 * TrialBoardTime(config) + std::chrono::seconds(2)};
  WaitEnd end{};
  if (!board.Await(finished, patience, &end, &why)) {
    switch (end) {
      case WaitEnd::kLinkFailed:
        return fail(TrialEnd::kLinkFailed, why);
      case WaitEnd::kInterrupted:
        return fail(TrialEnd::kInterrupted, why);
      case WaitEnd::kAmbiguous:
        return fail(TrialEnd::kAmbiguous, why);
      case WaitEnd::kSilent:
        return fail(TrialEnd::kNoAnswer, "during the trial, " + why);
      case WaitEnd::kBoardTime:
        return fail(TrialEnd::kNoAnswer,
                    "the trial did not finish within twice its length (" + why + ")");
    }
  }
  if (board.status().state == BoardState::kFault) {
    return fail(TrialEnd::kFaulted,
                "the board faulted: fault " + DescribeFault(board.status().fault));
  }
  // Idle before its end: every repetition makes a flexion and an extension window,
  // each either received or counted as broken on the bus.
  const std::size_t expected = 2u * config.repetitions;
  const std::uint64_t broken = board.incomplete_windows() - broken_before;
  if (out.windows.size() + broken < expected) {
    return fail(TrialEnd::kStopped, "the trial was stopped before its end, after " +
                                        std::to_string(out.windows.size()) + " of " +
                                        std::to_string(expected) +
                                        " windows (by another tool's stop?)");
  }
  out.end = TrialEnd::kCompleted;
  out.completed = true;
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
