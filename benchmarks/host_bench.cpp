// How steady this machine is, apart from STAC: three fixed workloads of about a scan's size,
// timed iteration by iteration, so that a p99 of STAC's benchmarks can be read against the
// machine's own spread (docs/benchmarks.md, "The host's steadiness"). Each takes about 2 ms.
//   BM_HostAlu           a dependent multiply-add chain: the core alone, no memory
//   BM_HostRandomReads   reads at random over a 4.5 MB table (the segmenter's fine grid's size)
//   BM_HostStream        reads six 4 MB blocks (six scans of 32-byte points) three times
// Each reports median_ms, p99_ms, max_ms, p99_over_median (wall clock; 2000 iterations) and
// slow_blocks (timing_stats.hpp: the machine slowed down for stretches, not single iterations).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <vector>

#include "benchmarks/timing_stats.hpp"

namespace {

void report(benchmark::State& state, std::vector<double> times) {
  using stac::benchmarks::quantile;
  std::vector<double> sorted = times;
  std::sort(sorted.begin(), sorted.end());
  const double median = quantile(sorted, 0.5);
  state.counters["median_ms"] = median;
  state.counters["p99_ms"] = quantile(sorted, 0.99);
  state.counters["max_ms"] = sorted.back();
  state.counters["p99_over_median"] = quantile(sorted, 0.99) / median;
  state.counters["slow_blocks"] = stac::benchmarks::slow_blocks(std::move(times), median);
}

template <typename Work>
void timed(benchmark::State& state, Work&& work) {
  std::vector<double> times;
  times.reserve(state.max_iterations);
  std::uint64_t k = 0;
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    benchmark::DoNotOptimize(work(k++));
    times.push_back(
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
  }
  report(state, std::move(times));
}

void BM_HostAlu(benchmark::State& state) {
  timed(state, [](std::uint64_t k) {
    std::uint64_t x = k;
    for (int i = 0; i < 2'000'000; ++i) x = x * 6364136223846793005ull + 1442695040888963407ull;
    return x;
  });
}
BENCHMARK(BM_HostAlu)->Iterations(2000)->Unit(benchmark::kMillisecond);

void BM_HostRandomReads(benchmark::State& state) {
  constexpr std::uint32_t kEntries = 1'179'648;  // 4.5 MB of 4-byte entries
  std::vector<std::uint32_t> table(kEntries);
  for (std::uint32_t i = 0; i < kEntries; ++i) table[i] = i * 2654435761u;
  timed(state, [&](std::uint64_t k) {
    std::uint32_t j = static_cast<std::uint32_t>(k), sum = 0;
    for (int i = 0; i < 1'000'000; ++i) {
      j = j * 1103515245u + 12345u;
      sum += table[j % kEntries];
    }
    return sum;
  });
}
BENCHMARK(BM_HostRandomReads)->Iterations(2000)->Unit(benchmark::kMillisecond);

void BM_HostStream(benchmark::State& state) {
  constexpr std::size_t kBlockWords = 4'000'000 / 8;
  std::vector<std::uint64_t> blocks(6 * kBlockWords);
  for (std::size_t i = 0; i < blocks.size(); ++i) blocks[i] = i;
  timed(state, [&](std::uint64_t k) {
    std::uint64_t sum = k;
    for (int pass = 0; pass < 3; ++pass) {
      for (std::size_t i = 0; i < blocks.size(); i += 4) sum += blocks[i];  // each 32-byte record
    }
    return sum;
  });
}
BENCHMARK(BM_HostStream)->Iterations(2000)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
