// rt::Wakeup (a futex: a consumer sleeps until its producer notifies) and rt::Counters.
#include "rt/wakeup.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <thread>

#include "rt/counters.hpp"
#include "rt/spsc_ring.hpp"

namespace stac::rt {
namespace {

static_assert(noexcept(std::declval<Wakeup&>().notify()));
static_assert(noexcept(std::declval<Wakeup&>().wait(0, 1)));

TEST(Wakeup, ANotifyBeforeTheWaitIsNotLost) {
  Wakeup w;
  const std::uint32_t seen = w.generation();
  w.notify();
  EXPECT_TRUE(w.wait(seen, 10'000'000'000)) << "returned at once, with the notify seen";
}

TEST(Wakeup, AWaitWithoutNotifyEndsAtItsTimeoutAndSaysSo) {
  Wakeup w;
  EXPECT_FALSE(w.wait(w.generation(), 1'000'000));
}

// Producer and consumer through a ring, the consumer asleep whenever the ring is empty: every
// item arrives and no wait ends by its timeout (a lost wake-up would leave the consumer asleep
// for its whole timeout).
TEST(Wakeup, NoWakeUpIsLostBetweenTwoThreads) {
  constexpr int kItems = 20000;
  SpscRing<int> ring(64);
  Wakeup has_items, has_room;
  int timeouts = 0;
  long long sum = 0;
  std::thread consumer([&] {
    for (int got = 0; got < kItems;) {
      const std::uint32_t seen = has_items.generation();
      int v = 0;
      if (ring.try_pop(v)) {
        sum += v;
        ++got;
        has_room.notify();
        continue;
      }
      if (!has_items.wait(seen, 5'000'000'000)) ++timeouts;
    }
  });
  for (int i = 1; i <= kItems;) {
    const std::uint32_t seen = has_room.generation();
    if (ring.try_push(i)) {
      ++i;
      has_items.notify();
      continue;
    }
    (void)has_room.wait(seen, 5'000'000'000);
  }
  consumer.join();
  EXPECT_EQ(sum, static_cast<long long>(kItems) * (kItems + 1) / 2);
  EXPECT_EQ(timeouts, 0);
}

enum class TestCount : std::size_t { kA, kB, kCount };

TEST(Counters, EachCounterIsItsOwnAndReadableFromAnotherThread) {
  Counters<TestCount> c;
  static_assert(Counters<TestCount>::kSize == 2);
  std::thread writer([&] {
    for (int i = 0; i < 1000; ++i) c.add(TestCount::kA);
    c.set(TestCount::kB, 42);
  });
  writer.join();
  EXPECT_EQ(c.get(TestCount::kA), 1000u);
  EXPECT_EQ(c.get(TestCount::kB), 42u);
  c.add(TestCount::kB, 8);
  EXPECT_EQ(c.get(TestCount::kB), 50u);
}

}  // namespace
}  // namespace stac::rt
