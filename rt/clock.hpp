// Clocks in integer nanoseconds (STYLE rule 10).
#pragma once

#include <cstdint>

namespace stac::rt {

// CLOCK_MONOTONIC: for latencies and timeouts.
std::int64_t monotonic_ns() noexcept;
// CLOCK_REALTIME: nanoseconds since the Unix epoch, for stamps when the source gives none.
std::int64_t realtime_ns() noexcept;
// CLOCK_THREAD_CPUTIME_ID: the CPU time of the calling thread, for a stage's cost on one core
// whatever else the machine does.
std::int64_t thread_cpu_ns() noexcept;

}  // namespace stac::rt
