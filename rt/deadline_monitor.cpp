#include "rt/deadline_monitor.hpp"

#include <algorithm>
#include <cmath>

namespace stac::rt {

LatencyHistogram::LatencyHistogram(std::int64_t max_ns, std::size_t bins)
    : width_ns_(std::max<std::int64_t>(
          1, max_ns / static_cast<std::int64_t>(std::max<std::size_t>(bins, 1)))),
      bins_(std::max<std::size_t>(bins, 1)),
      counts_(std::make_unique<std::uint64_t[]>(bins_ + 1)) {}

void LatencyHistogram::add(std::int64_t ns) noexcept {
  ns = std::max<std::int64_t>(ns, 0);
  const auto bin = static_cast<std::size_t>(ns / width_ns_);
  ++counts_[std::min(bin, bins_)];
  ++count_;
  max_ = std::max(max_, ns);
}

std::int64_t LatencyHistogram::percentile(double q) const noexcept {
  if (count_ == 0) return 0;
  q = std::clamp(q, 0.0, 1.0);
  // The smallest bin whose cumulative count reaches ceil(q * count) (at least the first sample).
  const auto rank = std::max<std::uint64_t>(
      1, static_cast<std::uint64_t>(std::ceil(q * static_cast<double>(count_))));
  std::uint64_t seen = 0;
  for (std::size_t b = 0; b < bins_; ++b) {
    seen += counts_[b];
    if (seen >= rank) return std::min(max_, static_cast<std::int64_t>(b + 1) * width_ns_);
  }
  return max_;
}

DeadlineMonitor::DeadlineMonitor(const DeadlineConfig& config, std::size_t stages)
    : config_(config), end_to_end_(config.histogram_max_ns, config.histogram_bins) {
  stages_.reserve(stages);
  for (std::size_t i = 0; i < stages; ++i)
    stages_.emplace_back(config.histogram_max_ns, config.histogram_bins);
}

bool DeadlineMonitor::record(std::span<const std::int64_t> stage_ns,
                             std::int64_t end_to_end_ns) noexcept {
  for (std::size_t i = 0; i < stages_.size() && i < stage_ns.size(); ++i)
    stages_[i].add(stage_ns[i]);
  end_to_end_.add(end_to_end_ns);
  if (end_to_end_ns <= config_.budget_ns) return true;
  ++misses_;
  return false;
}

}  // namespace stac::rt
