#include "replay/replay_pacing.hpp"

#include <sys/prctl.h>
#include <time.h>

#include <algorithm>
#include <cerrno>
#include <cmath>

#include "rt/clock.hpp"

namespace stac::replay {
namespace {

constexpr std::int64_t kSpinNs = 50'000;       // busy-wait the last 50 us before a send
constexpr std::int64_t kSliceNs = 20'000'000;  // longest single sleep: the stop flag's latency
constexpr std::size_t kHistogramUs = 100'000;  // 1 us bins up to 100 ms, then one overflow bin

}  // namespace

std::int64_t ReplayClock::offset_ns(std::uint64_t pass, std::int64_t stamp_ns) const noexcept {
  const double recorded = static_cast<double>(pass) * static_cast<double>(pass_period_ns) +
                          static_cast<double>(stamp_ns - first_stamp_ns);
  return std::llround(recorded / rate);
}

void wait_until(std::int64_t due_ns, const std::atomic<bool>& stop) noexcept {
  thread_local bool slack_set = false;
  if (!slack_set) {
    (void)::prctl(PR_SET_TIMERSLACK, 1000UL, 0UL, 0UL, 0UL);
    slack_set = true;
  }
  for (std::int64_t now = rt::monotonic_ns(); due_ns - now > kSpinNs; now = rt::monotonic_ns()) {
    if (stop.load(std::memory_order_relaxed)) return;
    const std::int64_t wake = std::min(due_ns - kSpinNs, now + kSliceNs);
    timespec ts{};
    ts.tv_sec = static_cast<time_t>(wake / 1'000'000'000);
    ts.tv_nsec = static_cast<long>(wake % 1'000'000'000);
    while (::clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
      if (stop.load(std::memory_order_relaxed)) return;
    }
  }
  while (rt::monotonic_ns() < due_ns) {
    if (stop.load(std::memory_order_relaxed)) return;
  }
}

PacingStats::PacingStats() : histogram_(kHistogramUs + 1, 0) {}

void PacingStats::add(std::int64_t error_ns) noexcept {
  const auto bin = static_cast<std::size_t>(std::max<std::int64_t>(error_ns, 0) / 1000);
  ++histogram_[std::min(bin, kHistogramUs)];
  ++count_;
  max_ns_ = std::max(max_ns_, error_ns);
}

std::int64_t PacingStats::percentile_ns(double q) const noexcept {
  if (count_ == 0) return -1;
  const auto rank = std::max<std::uint64_t>(
      static_cast<std::uint64_t>(std::ceil(q * static_cast<double>(count_))), 1);
  std::uint64_t seen = 0;
  for (std::size_t i = 0; i < histogram_.size(); ++i) {
    seen += histogram_[i];
    if (seen >= rank) return static_cast<std::int64_t>(i) * 1000;
  }
  return static_cast<std::int64_t>(kHistogramUs) * 1000;
}

}  // namespace stac::replay
