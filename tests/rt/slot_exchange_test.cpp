#include "rt/slot_exchange.hpp"

#include <gtest/gtest.h>

#include <array>
#include <thread>

namespace stac::rt {
namespace {

struct Frame {
  std::uint64_t sequence = 0;
  std::array<std::uint64_t, 64> payload{};
};

TEST(SlotExchange, HandsSlotsOverInOrder) {
  SlotExchange<Frame> x(3, [] { return Frame{}; });
  EXPECT_EQ(x.take(), nullptr);
  x.current().sequence = 1;
  EXPECT_TRUE(x.publish());
  x.current().sequence = 2;
  EXPECT_TRUE(x.publish());
  Frame* f = x.take();
  ASSERT_NE(f, nullptr);
  EXPECT_EQ(f->sequence, 1u);
  EXPECT_EQ(x.take(), f);  // still held
  x.release();
  f = x.take();
  ASSERT_NE(f, nullptr);
  EXPECT_EQ(f->sequence, 2u);
  x.release();
  EXPECT_EQ(x.take(), nullptr);
  EXPECT_EQ(x.published(), 2u);
}

TEST(SlotExchange, DropsNewestWhenTheConsumerHoldsEverySlot) {
  SlotExchange<Frame> x(2, [] { return Frame{}; });
  x.current().sequence = 1;
  ASSERT_TRUE(x.publish());
  x.current().sequence = 2;
  EXPECT_FALSE(x.publish());  // slot 1 not consumed: the producer keeps its slot
  EXPECT_EQ(x.dropped(), 1u);
  Frame* f = x.take();
  ASSERT_NE(f, nullptr);
  EXPECT_EQ(f->sequence, 1u);  // the unconsumed slot was never overwritten
  x.release();
  x.current().sequence = 3;
  EXPECT_TRUE(x.publish());
  f = x.take();
  ASSERT_NE(f, nullptr);
  EXPECT_EQ(f->sequence, 3u);
}

TEST(SlotExchange, NeverSharesASlotBetweenThreads) {
  constexpr std::uint64_t kFrames = 20000;
  SlotExchange<Frame> x(4, [] { return Frame{}; });
  std::thread producer([&] {
    for (std::uint64_t i = 1; i <= kFrames; ++i) {
      Frame& f = x.current();
      f.sequence = i;
      f.payload.fill(i);
      while (!x.publish()) std::this_thread::yield();  // this test wants every frame
    }
  });
  std::uint64_t expected = 1;
  while (expected <= kFrames) {
    if (Frame* f = x.take()) {
      ASSERT_EQ(f->sequence, expected);
      for (std::uint64_t v : f->payload) ASSERT_EQ(v, expected);  // never half-written
      x.release();
      ++expected;
    } else {
      std::this_thread::yield();
    }
  }
  producer.join();
}

}  // namespace
}  // namespace stac::rt
