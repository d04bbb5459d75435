// Latency bookkeeping of a live pipeline, in fixed memory: a histogram per stage and one for the
// end-to-end latency (the scan's last packet to its publication), with percentiles, the maximum
// and the count of scans over the configured budget. One thread records (the publisher);
// read the figures from it, or after it has been joined.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

namespace stac::rt {

// Linear bins of width max_ns / bins over [0, max_ns); later samples fall in an overflow bin.
// Percentiles are the upper edge of the bin that holds them (overflow: the exact maximum), so
// they overestimate by at most one bin width.
class LatencyHistogram {
 public:
  LatencyHistogram(std::int64_t max_ns, std::size_t bins);

  void add(std::int64_t ns) noexcept;  // negative latencies count as 0
  // q in [0, 1]; 0 when empty.
  [[nodiscard]] std::int64_t percentile(double q) const noexcept;
  [[nodiscard]] std::int64_t max_ns() const noexcept { return max_; }
  [[nodiscard]] std::uint64_t count() const noexcept { return count_; }
  [[nodiscard]] std::uint64_t overflow() const noexcept { return counts_[bins_]; }

 private:
  std::int64_t width_ns_;
  std::size_t bins_;
  std::unique_ptr<std::uint64_t[]> counts_;  // bins_ + 1 (overflow)
  std::uint64_t count_ = 0;
  std::int64_t max_ = 0;
};

struct DeadlineConfig {
  std::int64_t budget_ns = 100'000'000;           // end-to-end budget (one scan period at 10 Hz)
  std::int64_t histogram_max_ns = 1'000'000'000;  // histogram range (overflow beyond)
  std::size_t histogram_bins = 2000;              // 0.5 ms bins over 1 s
};

class DeadlineMonitor {
 public:
  DeadlineMonitor(const DeadlineConfig& config, std::size_t stages);

  // One published scan: its per-stage latencies (stages() values) and end to end. True when
  // it met the budget (end_to_end_ns <= budget_ns); a miss is counted otherwise.
  bool record(std::span<const std::int64_t> stage_ns, std::int64_t end_to_end_ns) noexcept;

  [[nodiscard]] std::uint64_t misses() const noexcept { return misses_; }
  [[nodiscard]] std::int64_t budget_ns() const noexcept { return config_.budget_ns; }
  [[nodiscard]] const LatencyHistogram& end_to_end() const noexcept { return end_to_end_; }
  [[nodiscard]] const LatencyHistogram& stage(std::size_t i) const noexcept { return stages_[i]; }
  [[nodiscard]] std::size_t stages() const noexcept { return stages_.size(); }

 private:
  DeadlineConfig config_;
  std::vector<LatencyHistogram> stages_;
  LatencyHistogram end_to_end_;
  std::uint64_t misses_ = 0;
};

}  // namespace stac::rt
