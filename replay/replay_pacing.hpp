// The pacing shared by the replays (UdpReplay, TcpReplay): one absolute schedule on
// CLOCK_MONOTONIC that several replays of the same capture can share, the wait for a due time
// (clock_nanosleep TIMER_ABSTIME to shortly before, then a spin, so sleep errors never
// accumulate), and the pacing error statistics (1 us histogram).
#pragma once

#include <atomic>
#include <cstdint>
#include <vector>

namespace stac::replay {

// Capture time first_stamp_ns (+ pass x pass_period_ns) is due at start_ns; recorded time
// differences are divided by rate (> 0).
struct ReplayClock {
  std::int64_t start_ns = 0;        // CLOCK_MONOTONIC
  std::int64_t first_stamp_ns = 0;  // capture time (ns since the Unix epoch) due at start_ns
  std::int64_t pass_period_ns = 0;  // recorded time from one pass's start to the next one's
  double rate = 1.0;

  // ns after start_ns at which capture time stamp_ns of pass `pass` is due.
  std::int64_t offset_ns(std::uint64_t pass, std::int64_t stamp_ns) const noexcept;
};

// Sleeps until CLOCK_MONOTONIC reaches due_ns, or returns early once `stop` is set (seen within
// 20 ms when set by another thread; at once on a signal). Lowers the calling thread's timer
// slack to 1 us the first time (the default 50 us would overshoot into the spin margin).
void wait_until(std::int64_t due_ns, const std::atomic<bool>& stop) noexcept;

// |send time - scheduled time| of every send, in 1 us bins up to 100 ms (one overflow bin).
class PacingStats {
 public:
  PacingStats();  // allocates the histogram; add() does not allocate
  void add(std::int64_t error_ns) noexcept;
  std::uint64_t count() const noexcept { return count_; }
  // Floor to 1 us; -1 when nothing was added.
  std::int64_t median_ns() const noexcept { return percentile_ns(0.5); }
  std::int64_t p99_ns() const noexcept { return percentile_ns(0.99); }
  std::int64_t max_ns() const noexcept { return count_ == 0 ? -1 : max_ns_; }

 private:
  std::int64_t percentile_ns(double q) const noexcept;
  std::vector<std::uint64_t> histogram_;
  std::uint64_t count_ = 0;
  std::int64_t max_ns_ = 0;
};

}  // namespace stac::replay
