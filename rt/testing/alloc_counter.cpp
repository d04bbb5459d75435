#include "rt/testing/alloc_counter.hpp"

#include <atomic>
#include <cerrno>
#include <cstddef>
#include <cstdlib>
#include <new>

#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define STAC_ALLOC_COUNTER_NEW_ONLY 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer)
#define STAC_ALLOC_COUNTER_NEW_ONLY 1
#endif
#endif

namespace {

// Counted always (two relaxed atomic adds); a counter reads the difference over its region.
std::atomic<std::uint64_t> g_allocations{0};
std::atomic<std::uint64_t> g_bytes{0};

inline void count(std::size_t n) noexcept {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  g_bytes.fetch_add(n, std::memory_order_relaxed);
}

}  // namespace

#ifndef STAC_ALLOC_COUNTER_NEW_ONLY
// glibc's own entry points: the interposed functions forward to them (their reserved names
// are glibc's).
// NOLINTBEGIN(bugprone-reserved-identifier,readability-identifier-naming)
extern "C" {
void* __libc_malloc(std::size_t);
void* __libc_calloc(std::size_t, std::size_t);
void* __libc_realloc(void*, std::size_t);
void* __libc_memalign(std::size_t, std::size_t);
void __libc_free(void*);

void* malloc(std::size_t n) {
  count(n);
  return __libc_malloc(n);
}
void* calloc(std::size_t n, std::size_t size) {
  count(n * size);
  return __libc_calloc(n, size);
}
void* realloc(void* p, std::size_t n) {
  count(n);
  return __libc_realloc(p, n);
}
void free(void* p) {
  __libc_free(p);
}
void* memalign(std::size_t alignment, std::size_t n) {
  count(n);
  return __libc_memalign(alignment, n);
}
void* aligned_alloc(std::size_t alignment, std::size_t n) {
  count(n);
  return __libc_memalign(alignment, n);
}
int posix_memalign(void** out, std::size_t alignment, std::size_t n) {
  count(n);
  void* p = __libc_memalign(alignment, n);
  if (p == nullptr) return ENOMEM;
  *out = p;
  return 0;
}
}
// NOLINTEND(bugprone-reserved-identifier,readability-identifier-naming)
#else
// Under a sanitizer: count operator new, allocate through malloc (which the sanitizer owns).
void* operator new(std::size_t n) {
  count(n);
  if (void* p = std::malloc(n == 0 ? 1 : n)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t n) {
  return operator new(n);
}
void* operator new(std::size_t n, const std::nothrow_t&) noexcept {
  count(n);
  return std::malloc(n == 0 ? 1 : n);
}
void* operator new[](std::size_t n, const std::nothrow_t& t) noexcept {
  return operator new(n, t);
}
void operator delete(void* p) noexcept {
  std::free(p);
}
void operator delete[](void* p) noexcept {
  std::free(p);
}
void operator delete(void* p, std::size_t) noexcept {
  std::free(p);
}
void operator delete[](void* p, std::size_t) noexcept {
  std::free(p);
}
#endif

namespace stac::rt::testing {

AllocationCounter::AllocationCounter() noexcept
    : start_allocations_(g_allocations.load(std::memory_order_acquire)),
      start_bytes_(g_bytes.load(std::memory_order_acquire)) {}

void AllocationCounter::stop() noexcept {
  if (!running_) return;
  stop_allocations_ = g_allocations.load(std::memory_order_acquire);
  stop_bytes_ = g_bytes.load(std::memory_order_acquire);
  running_ = false;
}

std::uint64_t AllocationCounter::allocations() const noexcept {
  return (running_ ? g_allocations.load(std::memory_order_acquire) : stop_allocations_) -
         start_allocations_;
}

std::uint64_t AllocationCounter::bytes() const noexcept {
  return (running_ ? g_bytes.load(std::memory_order_acquire) : stop_bytes_) - start_bytes_;
}

bool AllocationCounter::interposed() noexcept {
#ifdef STAC_ALLOC_COUNTER_NEW_ONLY
  return false;
#else
  return true;
#endif
}

}  // namespace stac::rt::testing
