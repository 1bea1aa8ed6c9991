// The single-producer single-consumer ring (mjc/core/spsc_queue.h) against a plain
// model of a bounded FIFO: values come out in the order they went in, a full ring
// refuses and counts the value, an empty one gives nothing, across many wraps of its
// indices. Runs on the host and on the Cortex-M4.
#include <cstdint>

#include "mjc/core/spsc_queue.h"
#include "vector_test.h"

namespace {

using mjc::lockfree::SpscQueue;

MJC_VECTOR_TEST(SpscQueue, FullQueueDropsAndCounts) {
  SpscQueue<int, 4> q;
  for (int i = 0; i < 4; ++i) VT_EXPECT_TRUE(q.Push(i));
  VT_EXPECT_TRUE(!q.Push(99));
  VT_EXPECT_EQ(q.dropped(), 1u);
  int v = -1;
  for (int i = 0; i < 4; ++i) {
    VT_EXPECT_TRUE(q.Pop(&v));
    VT_EXPECT_EQ(v, i);
  }
  VT_EXPECT_TRUE(!q.Pop(&v));
  VT_EXPECT_EQ(v, 3);  // an empty Pop leaves the output alone
}

MJC_VECTOR_TEST(SpscQueue, EmptyQueueGivesNothing) {
  SpscQueue<std::uint32_t, 2> q;
  std::uint32_t v = 7;
  VT_EXPECT_TRUE(!q.Pop(&v));
  VT_EXPECT_EQ(v, 7u);
  VT_EXPECT_TRUE(q.Front() == nullptr);
  VT_EXPECT_EQ(q.dropped(), 0u);
}

// Random bursts of pushes and pops over many wraps against the model: the producer
// pushes consecutive numbers, so the consumer must see them consecutively, and a push
// fails exactly when the model holds kCapacity values.
MJC_VECTOR_TEST(SpscQueue, StaysAFifoOverManyWraps) {
  constexpr std::uint32_t kCapacity = 8;
  SpscQueue<std::uint32_t, kCapacity> q;
  mjc::vt::Rng rng(1201);
  std::uint32_t next_in = 0, next_out = 0, refused = 0;
  for (int round = 0; round < 2000; ++round) {
    const int pushes = static_cast<int>(rng.Next() % 11);
    for (int i = 0; i < pushes; ++i) {
      const bool full = next_in - next_out == kCapacity;  // the model
      const bool pushed = q.Push(next_in);
      VT_EXPECT_EQ(pushed, !full);
      if (pushed) {
        ++next_in;
      } else {
        ++refused;
      }
    }
    const int pops = static_cast<int>(rng.Next() % 11);
    for (int i = 0; i < pops; ++i) {
      std::uint32_t v = 0;
      const bool popped = q.Pop(&v);
      VT_EXPECT_EQ(popped, next_out != next_in);
      if (!popped) break;
      VT_EXPECT_EQ(v, next_out);
      ++next_out;
    }
  }
  VT_EXPECT_EQ(q.dropped(), refused);
  VT_EXPECT_TRUE(next_out > 50 * kCapacity);  // the indices wrapped many times
  VT_EXPECT_TRUE(refused > 0);
}

// Front/DropFront: the oldest value in place, the same one Pop would give.
MJC_VECTOR_TEST(SpscQueue, FrontIsTheOldestUntilDropped) {
  struct Frame {
    std::uint32_t id;
    std::uint8_t data[8];
  };
  SpscQueue<Frame, 4> q;
  for (std::uint32_t i = 0; i < 6; ++i) {  // wrap once: in 0..5, out 0..5
    VT_EXPECT_TRUE(q.Push(Frame{0x100 + i, {static_cast<std::uint8_t>(i)}}));
    if (i >= 2) {
      const Frame* f = q.Front();
      VT_EXPECT_TRUE(f != nullptr);
      if (f == nullptr) return;
      VT_EXPECT_EQ(f->id, 0x100 + i - 2);
      VT_EXPECT_EQ(f->data[0], i - 2);
      VT_EXPECT_TRUE(q.Front() == f);  // peeking does not consume
      q.DropFront();
    }
  }
  Frame out{};
  VT_EXPECT_TRUE(q.Pop(&out));
  VT_EXPECT_EQ(out.id, 0x104u);
  const Frame* last = q.Front();
  VT_EXPECT_TRUE(last != nullptr);
  if (last == nullptr) return;
  VT_EXPECT_EQ(last->id, 0x105u);
  q.DropFront();
  VT_EXPECT_TRUE(q.Front() == nullptr);
}

}  // namespace
