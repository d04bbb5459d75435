#include "rt/deadline_monitor.hpp"

#include <gtest/gtest.h>

#include <array>

#include "rt/testing/alloc_counter.hpp"

namespace stac::rt {
namespace {

TEST(LatencyHistogram, PercentilesAreTheUpperEdgeOfTheBinHoldingThem) {
  LatencyHistogram h(1000, 100);                // 10 ns bins
  EXPECT_EQ(h.percentile(0.5), 0);              // empty
  for (int i = 1; i <= 100; ++i) h.add(i * 5);  // 5..500 ns
  EXPECT_EQ(h.count(), 100u);
  EXPECT_EQ(h.percentile(0.5), 260);  // the 50th sample, 250 ns, is in bin [250, 260)
  EXPECT_EQ(h.percentile(1.0), 500);  // never above the exact maximum
  EXPECT_EQ(h.max_ns(), 500);
  EXPECT_EQ(h.percentile(0.0), 10);  // the first sample's bin [0, 10)
}

TEST(LatencyHistogram, LateSamplesGoToOverflowAndTheExactMaximumStillShows) {
  LatencyHistogram h(1000, 10);
  h.add(-5);  // clock step backwards: counted as 0
  h.add(999);
  h.add(5000);
  EXPECT_EQ(h.overflow(), 1u);
  EXPECT_EQ(h.percentile(1.0), 5000);
  EXPECT_EQ(h.max_ns(), 5000);
  EXPECT_EQ(h.percentile(0.3), 100);  // the 0 in the first bin
}

TEST(DeadlineMonitor, CountsMissesOfTheBudgetAndKeepsOneHistogramPerStage) {
  DeadlineMonitor m({.budget_ns = 100, .histogram_max_ns = 1000, .histogram_bins = 100}, 3);
  ASSERT_EQ(m.stages(), 3u);
  const std::array<std::int64_t, 3> stages{10, 20, 30};
  EXPECT_TRUE(m.record(stages, 100));   // on the budget: met
  EXPECT_FALSE(m.record(stages, 101));  // one over: missed
  EXPECT_TRUE(m.record(stages, 60));
  EXPECT_EQ(m.misses(), 1u);
  EXPECT_EQ(m.end_to_end().count(), 3u);
  EXPECT_EQ(m.end_to_end().max_ns(), 101);
  EXPECT_EQ(m.stage(2).max_ns(), 30);
  EXPECT_EQ(m.stage(0).count(), 3u);
}

TEST(DeadlineMonitor, RecordNeverAllocates) {
  DeadlineMonitor m({}, 4);
  const std::array<std::int64_t, 4> stages{1000, 2000, 3000, 4000};
  testing::AllocationCounter counter;
  for (int i = 0; i < 10000; ++i) (void)m.record(stages, i * 100'000);
  counter.stop();
  EXPECT_EQ(counter.allocations(), 0u);
  static_assert(noexcept(m.record(stages, 0)));
}

}  // namespace
}  // namespace stac::rt
