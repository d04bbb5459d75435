// Tracker update time on one core: N moving targets plus clutter per scan at 10 Hz, the steady
// state after warm-up (tracks confirmed, clutter spawning and dying every scan).
#include <benchmark/benchmark.h>

#include <cmath>
#include <random>
#include <vector>

#include "perception/tracking/tracker.hpp"

namespace {

using namespace stac::tracking;

void BM_TrackerUpdate(benchmark::State& state) {
  const auto targets = static_cast<std::uint32_t>(state.range(0));
  const std::uint32_t clutter = targets / 4;
  Tracker tracker(TrackerConfig{});
  TrackerOutput out(tracker.config().max_tracks);
  std::mt19937 rng(1);
  std::normal_distribution<float> noise(0.0f, 0.1f);
  std::uniform_real_distribution<float> where(-60.0f, 60.0f);
  std::vector<Detection> dets(targets + clutter);
  std::int64_t k = 0;
  auto scan = [&] {
    const float t = static_cast<float>(k) * 0.1f;
    for (std::uint32_t i = 0; i < targets; ++i) {
      // Targets on a 4 m grid, each moving at up to 10 m/s on a slow circle.
      const float a = 0.2f * t + static_cast<float>(i);
      const float x = -50.0f + 4.0f * static_cast<float>(i % 25) + 3.0f * std::cos(a);
      const float y = -50.0f + 4.0f * static_cast<float>(i / 25) + 3.0f * std::sin(a);
      dets[i].centroid = Eigen::Vector3f(x + noise(rng), y + noise(rng), 0.8f);
      dets[i].segment = i;
    }
    for (std::uint32_t i = targets; i < targets + clutter; ++i) {
      dets[i].centroid = Eigen::Vector3f(where(rng), where(rng), 0.5f);
      dets[i].segment = i;
    }
    tracker.update(k++ * 100'000'000, dets, out);
  };
  for (int warm = 0; warm < 20; ++warm) scan();
  for (auto _ : state) scan();
  state.counters["tracks"] = static_cast<double>(out.tracks.size());
}
BENCHMARK(BM_TrackerUpdate)->Arg(50)->Arg(100)->Arg(200)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
