// Statistics of per-iteration times shared by the benchmarks.
#pragma once

#include <algorithm>
#include <cstddef>
#include <vector>

namespace stac::benchmarks {

// The q-quantile (0 <= q <= 1) of ascending `sorted` (not empty): the element at q x size, the
// last for q = 1.
inline double quantile(const std::vector<double>& sorted, double q) {
  return sorted[std::min(sorted.size() - 1,
                         static_cast<std::size_t>(q * static_cast<double>(sorted.size())))];
}

// Whether a benchmark's slow iterations came singly or in stretches: the fraction of blocks of
// 100 consecutive iterations (`times` in their order) whose median is over 1.2 x `median`, the
// median of all of them. Single slow iterations (an interrupt, a cache-cold scan) leave it at 0;
// a stretch where the machine runs slower (other guests on the host, docs/benchmarks.md "The
// host's steadiness") raises it.
inline double slow_blocks(std::vector<double> times, double median) {
  constexpr std::size_t kBlock = 100;
  std::size_t blocks = 0, slow = 0;
  for (std::size_t b = 0; b + kBlock <= times.size(); b += kBlock, ++blocks) {
    const auto first = times.begin() + static_cast<std::ptrdiff_t>(b);
    std::nth_element(first, first + kBlock / 2, first + kBlock);
    if (first[kBlock / 2] > 1.2 * median) ++slow;
  }
  return blocks == 0 ? 0.0 : static_cast<double>(slow) / static_cast<double>(blocks);
}

}  // namespace stac::benchmarks
