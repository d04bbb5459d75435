#include "rt/testing/alloc_counter.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "rt/fixed_vector.hpp"
#include "rt/spsc_ring.hpp"

namespace stac::rt::testing {
namespace {

// Keeps the compiler from eliding an allocation whose result is unused.
void escape(void* p) {
  asm volatile("" : : "g"(p) : "memory");
}

TEST(AllocationCounter, CountsOperatorNew) {
  AllocationCounter counter;
  auto p = std::make_unique<int>(3);
  escape(p.get());
  std::vector<int> v(100);
  escape(v.data());
  counter.stop();
  EXPECT_EQ(counter.allocations(), 2u);
  EXPECT_GE(counter.bytes(), sizeof(int) + 100 * sizeof(int));
}

TEST(AllocationCounter, CountsTheMallocFamilyWhenInterposed) {
  if (!AllocationCounter::interposed()) {
    GTEST_SKIP() << "SKIPPED: under a sanitizer only operator new is counted";
  }
  AllocationCounter counter;
  void* a = std::malloc(10);
  escape(a);
  void* b = std::calloc(2, 8);
  escape(b);
  a = std::realloc(a, 100);
  escape(a);
  std::free(a);
  std::free(b);
  counter.stop();
  EXPECT_EQ(counter.allocations(), 3u);
}

TEST(AllocationCounter, CountsOtherThreads) {
  AllocationCounter counter;
  std::thread t([] {
    std::string s(1000, 'x');
    escape(s.data());
  });
  t.join();
  counter.stop();
  EXPECT_GE(counter.allocations(), 1u);
}

TEST(AllocationCounter, SeesNothingInAFixedCapacitySteadyState) {
  FixedVector<double> v(1024);
  SpscRing<int> ring(16);
  AllocationCounter counter;
  for (int round = 0; round < 100; ++round) {
    v.clear();
    for (int i = 0; i < 1024; ++i) ASSERT_TRUE(v.push_back(i));
    int x = 0;
    for (int i = 0; i < 16; ++i) ASSERT_TRUE(ring.try_push(i));
    while (ring.try_pop(x)) escape(&x);
  }
  counter.stop();
  EXPECT_EQ(counter.allocations(), 0u);
}

TEST(AllocationCounter, StopFreezesTheCount) {
  AllocationCounter counter;
  counter.stop();
  auto p = std::make_unique<int>(1);
  escape(p.get());
  EXPECT_EQ(counter.allocations(), 0u);
}

}  // namespace
}  // namespace stac::rt::testing
