#include "rt/spsc_ring.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <thread>

namespace stac::rt {
namespace {

static_assert(noexcept(std::declval<SpscRing<int>&>().try_push(1)));
static_assert(noexcept(std::declval<SpscRing<int>&>().try_pop(std::declval<int&>())));

TEST(SpscRing, HoldsExactlyItsCapacity) {
  SpscRing<int> ring(3);
  EXPECT_EQ(ring.capacity(), 3u);
  EXPECT_TRUE(ring.try_push(1));
  EXPECT_TRUE(ring.try_push(2));
  EXPECT_TRUE(ring.try_push(3));
  EXPECT_FALSE(ring.try_push(4));
  EXPECT_EQ(ring.size(), 3u);
  int v = 0;
  EXPECT_TRUE(ring.try_pop(v));
  EXPECT_EQ(v, 1);
  EXPECT_TRUE(ring.try_push(4));  // wraps around
  for (int expected : {2, 3, 4}) {
    ASSERT_TRUE(ring.try_pop(v));
    EXPECT_EQ(v, expected);
  }
  EXPECT_FALSE(ring.try_pop(v));
  EXPECT_TRUE(ring.empty());
}

TEST(SpscRing, WrapsAroundManyTimes) {
  SpscRing<std::uint32_t> ring(5);
  std::uint32_t next_in = 0, next_out = 0;
  for (int round = 0; round < 1000; ++round) {
    const int n = round % 6;
    for (int i = 0; i < n; ++i) {
      if (ring.try_push(next_in)) ++next_in;
    }
    std::uint32_t v = 0;
    while (ring.try_pop(v)) ASSERT_EQ(v, next_out++);
  }
  EXPECT_EQ(next_in, next_out);
}

// Two threads, a million items: order kept, nothing lost or duplicated.
TEST(SpscRing, KeepsOrderAcrossThreads) {
  constexpr std::uint64_t kItems = 1'000'000;
  SpscRing<std::uint64_t> ring(64);
  std::thread producer([&] {
    for (std::uint64_t i = 0; i < kItems; ++i) {
      while (!ring.try_push(i)) std::this_thread::yield();
    }
  });
  std::uint64_t expected = 0;
  std::uint64_t v = 0;
  while (expected < kItems) {
    if (ring.try_pop(v)) {
      ASSERT_EQ(v, expected);
      ++expected;
    } else {
      std::this_thread::yield();
    }
  }
  producer.join();
  EXPECT_FALSE(ring.try_pop(v));
}

}  // namespace
}  // namespace stac::rt
