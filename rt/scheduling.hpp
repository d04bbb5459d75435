// Real-time scheduling of a live process, each step optional and each failure a value whose
// message says what was asked, why it was refused and what to change; the caller prints it once
// as a warning and runs on without it (a container without CAP_SYS_NICE / CAP_IPC_LOCK, a CPU
// that is not there).
//
//   if (auto r = rt::lock_memory(); !r) warn(r.error().message);          // at start-up
//   if (auto r = rt::apply_schedule("perception", s); !r) warn(...);      // in each thread
#pragma once

#include <string>
#include <utility>

#include "rt/expected.hpp"
#include "rt/unique_fd.hpp"

namespace stac::rt {

struct ThreadSchedule {
  int fifo_priority = 0;  // 1..99: SCHED_FIFO at this priority; 0: the default (SCHED_OTHER)
  int cpu = -1;           // pin to this CPU (0-based); -1: any CPU
};

// Checks the values (not the permissions): priority 0..99, cpu >= -1. Errors name `what`.
Status validate(const ThreadSchedule& s, const std::string& what);

// mlockall(MCL_CURRENT | MCL_FUTURE): no page fault on memory touched later.
Status lock_memory() noexcept;

// Applies `s` to the calling thread: CPU affinity, then the policy. Returns an error naming
// `thread` for the first part refused (the other part is still tried); nothing to do is true.
Status apply_schedule(const std::string& thread, const ThreadSchedule& s);

// A PM QoS request on the CPUs' wake-up latency (Linux /dev/cpu_dma_latency), held while the
// object lives: idle CPUs only enter states that wake within max_us microseconds. 0 keeps the
// idle loop polling, so that no core halts: a halted core (or a virtual machine's halted vCPU,
// which the host must schedule again) can take milliseconds to run a thread woken by a packet
// or a timer. What cyclictest and real-time tuning guides do; it costs power (cores never
// sleep). The device takes the value as a binary 32-bit integer; closing it ends the request.
class CpuLatencyRequest {
 public:
  static constexpr const char* kDevice = "/dev/cpu_dma_latency";
  // Opens `device` and writes max_us (>= 0). Errors say what to fix (root or CAP_SYS_ADMIN...).
  static Result<CpuLatencyRequest> hold(int max_us, const char* device = kDevice);
  // The current aggregate request of all holders (us), read from `device`.
  static Result<int> current(const char* device = kDevice);

 private:
  explicit CpuLatencyRequest(UniqueFd fd) noexcept : fd_(std::move(fd)) {}
  UniqueFd fd_;
};

// Names the calling thread (at most 15 characters shown in top/ps); best effort.
void name_thread(const char* name) noexcept;

}  // namespace stac::rt
