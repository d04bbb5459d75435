#include "rt/wakeup.hpp"

#include <linux/futex.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <cerrno>
#include <ctime>

namespace stac::rt {
namespace {

static_assert(sizeof(std::atomic<std::uint32_t>) == sizeof(std::uint32_t) &&
                  std::atomic<std::uint32_t>::is_always_lock_free,
              "a futex word is a plain 32-bit integer");

long futex(std::atomic<std::uint32_t>& word, int op, std::uint32_t value,
           const timespec* timeout) noexcept {
  return syscall(SYS_futex, reinterpret_cast<std::uint32_t*>(&word), op, value, timeout, nullptr,
                 FUTEX_BITSET_MATCH_ANY);
}

}  // namespace

bool Wakeup::wait(std::uint32_t seen, std::int64_t timeout_ns) noexcept {
  // The sleeper registers before it checks the generation; notify() bumps the generation before
  // it checks for sleepers (both sequentially consistent): one of them sees the other.
  // The futex can return without a notify of ours: a FUTEX_WAKE of an earlier notify() that
  // reached the kernel late (after that wait had ended and this one begun), or a signal. So the
  // wait goes on until the generation moves or an absolute deadline on CLOCK_MONOTONIC passes
  // (FUTEX_WAIT_BITSET measures its absolute timeout on that clock).
  timespec deadline{};
  clock_gettime(CLOCK_MONOTONIC, &deadline);
  const std::int64_t end_ns =
      static_cast<std::int64_t>(deadline.tv_sec) * 1'000'000'000 + deadline.tv_nsec + timeout_ns;
  deadline = {static_cast<std::time_t>(end_ns / 1'000'000'000),
              static_cast<long>(end_ns % 1'000'000'000)};
  sleepers_.fetch_add(1, std::memory_order_seq_cst);
  while (generation_.load(std::memory_order_seq_cst) == seen) {
    // Returns at once (EAGAIN) when the generation moved on before the kernel looked.
    if (futex(generation_, FUTEX_WAIT_BITSET_PRIVATE, seen, &deadline) != 0 && errno == ETIMEDOUT)
      break;
  }
  sleepers_.fetch_sub(1, std::memory_order_seq_cst);
  return generation_.load(std::memory_order_seq_cst) != seen;
}

void Wakeup::notify() noexcept {
  generation_.fetch_add(1, std::memory_order_seq_cst);
  if (sleepers_.load(std::memory_order_seq_cst) != 0)
    (void)futex(generation_, FUTEX_WAKE_PRIVATE, 1, nullptr);
}

}  // namespace stac::rt
