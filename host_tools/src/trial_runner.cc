#include "mjc/host/trial_runner.h"

#include <chrono>

#include "mjc/host/describe.h"

namespace mjc::host {

using protocol::BoardState;
using protocol::CommandCode;
using protocol::CommandOutcomeCode;
using protocol::TrialConfig;

std::chrono::milliseconds TrialBoardTime(const TrialConfig& config) {
  const double frequency_hz = config.frequency_mHz / 1000.0;
  const double seconds = config.repetitions / frequency_hz + 2 * config.rest_100ms / 10.0;
  return std::chrono::milliseconds(static_cast<std::int64_t>(seconds * 1000.0 + 0.5));
}

BoardTrial RunBoardTrial(BoardClient& board, const TrialConfig& config,
                         const std::function<void(const BoardWindow&)>& progress) {
  BoardTrial out;
  // The motion's binding ends with the trial, however it ends.
  struct Release {
    BoardClient& board;
    ~Release() { board.ReleaseMotion(); }
  } release{board};
  const auto fail = [&out](TrialEnd end, std::string why) {
    out.end = end;
    out.error = std::move(why);
    // Nothing of a motion that was not the one started is kept.
    if (end == TrialEnd::kWrongConfig) out.windows.clear();
    return out;
  };
  std::string why;
  board.TakeWindows();
  const std::uint64_t broken_before = board.incomplete_windows();
  // The configuration and the start naming it; the board's MotionConfig confirms it.
  const auto outcome = board.Start(config, kStartAnswerMs, &why);
  if (!outcome) {
    if (board.motion_mismatch()) return fail(TrialEnd::kWrongConfig, board.mismatch());
    if (board.interrupted()) return fail(TrialEnd::kInterrupted, why);
    if (board.ambiguous()) return fail(TrialEnd::kAmbiguous, why);
    return fail(board.link_failed() ? TrialEnd::kLinkFailed : TrialEnd::kNoAnswer, why);
  }
  if (*outcome != CommandOutcomeCode::kAccepted) {
    // Not idle: a latched fault is the usual reason, and it has a remedy to name.
    WaitEnd end{};
    const std::chrono::milliseconds second{1000};
    if (*outcome == CommandOutcomeCode::kRefusedNotIdle &&
        board.Await([&] { return board.status().heard; },
                    {second, ExchangeSilence(second)}, &end, &why) &&
        board.status().state == BoardState::kFault) {
      return fail(TrialEnd::kRefused, "the board refused the trial: it holds fault " +
                                          DescribeFault(board.status().fault) +
                                          "; clear it with mjc clear --node " +
                                          std::to_string(board.node()) +
                                          " once its cause is gone");
    }
    return fail(TrialEnd::kRefused,
                "the board refused the trial: " + board.RefusalMessage(*outcome));
  }
  // Followed at the board's pace: done when the board says it is idle again after
  // running. Its frames arrive in the order it sent them, and it sends a window's
  // frames before the heartbeat that reports the trial over, so every window is in by
  // then. Bounded by twice the trial's own length in the board's time, and by silence.
  const auto take_windows = [&] {
    for (BoardWindow& w : board.TakeWindows()) {
      if (progress) progress(w);
      out.windows.push_back(w);
    }
  };
  const Patience patience{2 * TrialBoardTime(config) + std::chrono::seconds(2)};
  WaitEnd end{};
  if (!board.AwaitMotionEnd(BoardState::kRunning, take_windows, patience, &end, &why)) {
    switch (end) {
      case WaitEnd::kLinkFailed:
        // Nothing can reach the board now; it stops on its own once our heartbeats
        // stay away for its host timeout.
        return fail(TrialEnd::kLinkFailed,
                    why + " during the trial; node " + std::to_string(board.node()) +
                        " stops the motion itself when it misses this host's heartbeats "
                        "(fault 302)");
      case WaitEnd::kInterrupted:
        return fail(TrialEnd::kInterrupted, why);
      case WaitEnd::kAmbiguous:
        return fail(TrialEnd::kAmbiguous, why);
      case WaitEnd::kWrongMotion:
        return fail(TrialEnd::kWrongConfig, why);
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

}  // namespace mjc::host
