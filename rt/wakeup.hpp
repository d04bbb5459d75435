// One thread sleeps until another has something for it (a futex): the consumer of a queue
// waits on it instead of polling with sleeps, the producer notifies after each push. A notify
// that finds nobody asleep costs two atomic operations and no system call. Async-signal-safe
// (notify() may be called from a signal handler). No allocation.
//
//   consumer: for (;;) { const auto seen = w.generation(); if (T* x = q.take()) {...; continue;}
//                        w.wait(seen, timeout_ns); }
//   producer: q.publish(...); w.notify();
#pragma once

#include <atomic>
#include <cstdint>

namespace stac::rt {

class Wakeup {
 public:
  // Consumer: read before looking for data, then passed to wait().
  [[nodiscard]] std::uint32_t generation() const noexcept {
    return generation_.load(std::memory_order_seq_cst);
  }
  // Consumer: sleeps until a notify() after generation() returned `seen`, or for timeout_ns
  // (> 0, measured on CLOCK_MONOTONIC). Returns at once when one came already. True when a
  // notify() came, false at the timeout only (a signal or a late wake-up of an earlier notify()
  // does not end the wait); either way, look for data again.
  bool wait(std::uint32_t seen, std::int64_t timeout_ns) noexcept;
  // Producer: wakes the consumer.
  void notify() noexcept;

 private:
  std::atomic<std::uint32_t> generation_{0};
  std::atomic<std::uint32_t> sleepers_{0};
};

}  // namespace stac::rt
