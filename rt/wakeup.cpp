#include "rt/wakeup.hpp"

#include <linux/futex.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <ctime>

namespace stac::rt {
namespace {

static_assert(sizeof(std::atomic<std::uint32_t>) == sizeof(std::uint32_t) &&
                  std::atomic<std::uint32_t>::is_always_lock_free,
              "a futex word is a plain 32-bit integer");

long futex(std::atomic<std::uint32_t>& word, int op, std::uint32_t value,
           const timespec* timeout) noexcept {
  return syscall(SYS_futex, reinterpret_cast<std::uint32_t*>(&word), op, value, timeout, nullptr,
                 0);
}

}  // namespace

bool Wakeup::wait(std::uint32_t seen, std::int64_t timeout_ns) noexcept {
  // The sleeper registers before it checks the generation; notify() bumps the generation before
  // it checks for sleepers (both sequentially consistent): one of them sees the other.
  sleepers_.fetch_add(1, std::memory_order_seq_cst);
  if (generation_.load(std::memory_order_seq_cst) == seen) {
    const timespec timeout{static_cast<std::time_t>(timeout_ns / 1'000'000'000),
                           static_cast<long>(timeout_ns % 1'000'000'000)};
    // Returns at once (EAGAIN) when the generation moved on before the kernel looked.
    (void)futex(generation_, FUTEX_WAIT_PRIVATE, seen, &timeout);
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
