// rt::Wakeup (a futex: a consumer sleeps until its producer notifies) and rt::Counters.
#include "rt/wakeup.hpp"

#include <gtest/gtest.h>
#include <pthread.h>

#include <atomic>
#include <chrono>
#include <csignal>
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

// A signal (handled, without SA_RESTART, so the futex returns EINTR) does not end a wait: it goes
// on until the notify() that comes after it. (The same path takes a FUTEX_WAKE of an earlier
// notify() that reaches the kernel only after a new wait has begun.)
extern "C" void ignore_signal(int) {}

TEST(Wakeup, ASignalDuringTheWaitDoesNotEndIt) {
  struct sigaction action {};
  action.sa_handler = ignore_signal;  // no SA_RESTART
  struct sigaction previous {};
  ASSERT_EQ(sigaction(SIGUSR1, &action, &previous), 0);
  Wakeup w;
  const std::uint32_t seen = w.generation();
  std::atomic<bool> waiting{false}, done{false}, woken{false};
  std::atomic<std::int64_t> waited_ns{0};
  std::thread waiter([&] {
    waiting = true;
    const auto start = std::chrono::steady_clock::now();
    woken = w.wait(seen, 10'000'000'000);
    waited_ns = std::chrono::duration_cast<std::chrono::nanoseconds>(
                    std::chrono::steady_clock::now() - start)
                    .count();
    done = true;
  });
  while (!waiting) std::this_thread::yield();
  for (int i = 0; i < 10; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    pthread_kill(waiter.native_handle(), SIGUSR1);
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  EXPECT_FALSE(done) << "the wait ended at a signal, without a notify";
  w.notify();
  waiter.join();
  sigaction(SIGUSR1, &previous, nullptr);
  EXPECT_TRUE(woken);
  EXPECT_GE(waited_ns.load(), 200'000'000);
}

// A wait without a notify lasts its whole timeout, whatever interrupts it.
TEST(Wakeup, AWaitEndsAtItsDeadlineEvenWhenInterrupted) {
  struct sigaction action {};
  action.sa_handler = ignore_signal;
  struct sigaction previous {};
  ASSERT_EQ(sigaction(SIGUSR1, &action, &previous), 0);
  Wakeup w;
  std::atomic<bool> done{false};
  bool woken = true;
  std::int64_t waited_ns = 0;
  std::thread waiter([&] {
    const auto start = std::chrono::steady_clock::now();
    woken = w.wait(w.generation(), 300'000'000);
    waited_ns = std::chrono::duration_cast<std::chrono::nanoseconds>(
                    std::chrono::steady_clock::now() - start)
                    .count();
    done = true;
  });
  while (!done) {
    pthread_kill(waiter.native_handle(), SIGUSR1);
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  waiter.join();
  sigaction(SIGUSR1, &previous, nullptr);
  EXPECT_FALSE(woken);
  EXPECT_GE(waited_ns, 300'000'000);
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
