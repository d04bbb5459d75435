#include "ego/pose_history.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <numbers>
#include <thread>

#include "rt/testing/alloc_counter.hpp"

namespace stac::ego {
namespace {

constexpr std::int64_t kMs = 1'000'000;
constexpr double kYawRate = 30.0 * std::numbers::pi / 180.0;  // rad/s

// A vehicle driving at 10 m/s along x while turning at 30 deg/s (not consistent: the two are
// independent so each is checked on its own): every quantity is a known function of time.
PoseSample truth(std::int64_t t_ns) {
  const double t = static_cast<double>(t_ns) * 1e-9;
  PoseSample p;
  p.stamp_ns = t_ns;
  p.position_m = {10.0 * t, 2.0, 0.5};
  p.attitude = Eigen::Quaterniond(Eigen::AngleAxisd(kYawRate * t, Eigen::Vector3d::UnitZ()));
  p.velocity_mps = {10.0, 0.0, 0.0};
  p.angular_rate_rps = {0.0, 0.0, kYawRate};
  return p;
}

double yaw_of(const Eigen::Quaterniond& q) {
  const Eigen::Vector3d x = q * Eigen::Vector3d::UnitX();
  return std::atan2(x.y(), x.x());
}

PoseHistoryConfig config(std::size_t capacity) {
  return {.capacity = capacity, .max_extrapolation_ns = 50 * kMs, .max_gap_ns = 100 * kMs};
}

// Samples every 5 ms from t = 0 (200 Hz, as the INS).
void fill(PoseHistory& h, int samples) {
  for (int i = 0; i < samples; ++i) EXPECT_TRUE(h.push(truth(i * 5 * kMs)));
}

TEST(PoseHistory, InterpolatesPositionLinearlyAndAttitudeBySlerp) {
  PoseHistory h(config(400));
  fill(h, 200);  // 1 s
  for (std::int64_t t = 0; t < 995 * kMs; t += 777'777) {
    const PoseLookup l = h.at(t);
    ASSERT_EQ(l.status, PoseStatus::kInterpolated) << t;
    const PoseSample e = truth(t);
    EXPECT_NEAR((l.pose.position_m - e.position_m).norm(), 0.0, 1e-9);
    EXPECT_NEAR(yaw_of(l.pose.attitude), yaw_of(e.attitude), 1e-9);  // constant rate: slerp exact
    EXPECT_EQ(l.pose.stamp_ns, t);
  }
}

TEST(PoseHistory, SaysWhenThereIsNoPoseAndExtrapolatesOnlyABoundedTime) {
  PoseHistory empty(PoseHistoryConfig{});
  EXPECT_EQ(empty.at(0).status, PoseStatus::kEmpty);
  EXPECT_FALSE(empty.at(0).ok());

  PoseHistory h(config(400));
  fill(h, 200);  // samples 0 .. 995 ms
  EXPECT_EQ(h.at(-1).status, PoseStatus::kTooOld);
  const PoseLookup ahead = h.at(995 * kMs + 30 * kMs);
  ASSERT_EQ(ahead.status, PoseStatus::kExtrapolated);
  EXPECT_NEAR((ahead.pose.position_m - truth(1025 * kMs).position_m).norm(), 0.0, 1e-9);
  EXPECT_NEAR(yaw_of(ahead.pose.attitude), yaw_of(truth(1025 * kMs).attitude), 1e-9);
  EXPECT_EQ(h.at(995 * kMs + 51 * kMs).status, PoseStatus::kTooNew);
  EXPECT_EQ(h.newest_stamp_ns(), 995 * kMs);
}

TEST(PoseHistory, ReportsGapsBetweenSamples) {
  PoseHistory h(
      PoseHistoryConfig{.capacity = 16, .max_extrapolation_ns = 0, .max_gap_ns = 100 * kMs});
  ASSERT_TRUE(h.push(truth(0)));
  ASSERT_TRUE(h.push(truth(300 * kMs)));  // INS silent for 300 ms
  EXPECT_EQ(h.at(150 * kMs).status, PoseStatus::kGap);
  EXPECT_FALSE(h.at(150 * kMs).ok());
}

TEST(PoseHistory, RejectsOutOfOrderAndNonFiniteSamplesAndCountsThem) {
  PoseHistory h(PoseHistoryConfig{.capacity = 8});
  EXPECT_TRUE(h.push(truth(10 * kMs)));
  EXPECT_FALSE(h.push(truth(10 * kMs)));  // same stamp
  EXPECT_FALSE(h.push(truth(5 * kMs)));   // older
  PoseSample bad = truth(20 * kMs);
  bad.position_m.x() = std::nan("");
  EXPECT_FALSE(h.push(bad));
  EXPECT_EQ(h.rejected(), 3u);
  EXPECT_EQ(h.pushed(), 1u);
}

TEST(PoseHistory, ARestartBeginsANewTimelineThatLookupsKeepTo) {
  PoseHistory h(config(64));
  fill(h, 40);  // 0..195 ms
  PoseSample moved = truth(50 * kMs);
  moved.position_m.y() = 100.0;  // the new timeline's poses are elsewhere
  EXPECT_FALSE(h.push(moved));   // older than the newest: refused by push
  ASSERT_TRUE(h.restart(moved));
  for (int i = 11; i < 20; ++i) {
    PoseSample p = truth(i * 5 * kMs);
    p.position_m.y() = 100.0;
    ASSERT_TRUE(h.push(p));
  }
  const PoseLookup mid = h.at(70 * kMs);
  ASSERT_TRUE(mid.ok()) << to_string(mid.status);
  EXPECT_DOUBLE_EQ(mid.pose.position_m.y(), 100.0);       // never the old timeline's sample
  EXPECT_EQ(h.at(20 * kMs).status, PoseStatus::kTooOld);  // before the new timeline
  PoseSample bad = truth(0);
  bad.position_m.x() = std::nan("");
  EXPECT_FALSE(h.restart(bad));
}

TEST(PoseHistory, KeepsTheNewestCapacityAfterWrappingAround) {
  PoseHistory h(config(100));
  fill(h, 1000);  // 10 times around
  EXPECT_EQ(h.at(100 * 5 * kMs).status, PoseStatus::kTooOld);
  const std::int64_t recent = 950 * 5 * kMs + 1234;
  const PoseLookup l = h.at(recent);
  ASSERT_EQ(l.status, PoseStatus::kInterpolated);
  EXPECT_NEAR((l.pose.position_m - truth(recent).position_m).norm(), 0.0, 1e-9);
}

TEST(PoseHistory, ReadersNeverSeeATornSampleWhileTheWriterRuns) {
  // A small ring the writer laps constantly: every interpolated position must still lie on the
  // line x = 10 t, y = 2, which a sample mixing two writes would leave.
  PoseHistory h(PoseHistoryConfig{.capacity = 64, .max_extrapolation_ns = 50 * kMs});
  constexpr std::uint64_t kWanted = 20'000;  // successful lookups while the writer runs
  std::atomic<bool> enough{false}, done{false};
  std::atomic<std::int64_t> newest{-1};
  std::thread writer([&] {
    // Until the reader has seen enough (on a loaded machine the two may rarely overlap),
    // bounded so a broken reader cannot hang the test.
    for (std::int64_t i = 0; i < 50'000'000 && !enough.load(std::memory_order_relaxed); ++i) {
      (void)h.push(truth(i * kMs));
      newest.store(i * kMs, std::memory_order_release);
    }
    done = true;
  });
  std::uint64_t ok = 0;
  while (!done && ok < kWanted) {
    const std::int64_t last = newest.load(std::memory_order_acquire);
    if (last < 20 * kMs) continue;
    const std::int64_t t = last - 20 * kMs + 333;
    const PoseLookup l = h.at(t);
    if (!l.ok()) continue;  // overtaken by the writer: allowed, but never a torn sample
    ++ok;
    ASSERT_NEAR(l.pose.position_m.x(), 10.0 * static_cast<double>(t) * 1e-9, 1e-6);
    ASSERT_NEAR(l.pose.position_m.y(), 2.0, 1e-12);
    ASSERT_NEAR(l.pose.attitude.norm(), 1.0, 1e-9);
  }
  enough = true;
  writer.join();
  EXPECT_EQ(ok, kWanted);
}

TEST(PoseHistory, LookupsAndPushesAllocateNothing) {
  static_assert(noexcept(std::declval<PoseHistory&>().push(std::declval<const PoseSample&>())));
  static_assert(noexcept(std::declval<const PoseHistory&>().at(0)));
  PoseHistory h(PoseHistoryConfig{.capacity = 256});
  rt::testing::AllocationCounter counter;
  for (int i = 0; i < 1000; ++i) {
    (void)h.push(truth(i * 5 * kMs));
    (void)h.at(i * 5 * kMs - 2 * kMs);
  }
  counter.stop();
  EXPECT_EQ(counter.allocations(), 0u);
}

}  // namespace
}  // namespace stac::ego
