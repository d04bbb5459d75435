// Bounded lock-free single-producer single-consumer ring (rigtorp/SPSCQueue style): head and tail
// on their own cache lines, each side caching the other's index. Storage is allocated once in the
// constructor. Full policy is the caller's: try_push returns false and the producer counts the
// drop (and decides whether that drops the newest item or reuses it).
#pragma once

#include <atomic>
#include <cstddef>
#include <memory>
#include <new>
#include <type_traits>

namespace stac::rt {

inline constexpr std::size_t kCacheLine = 64;

template <class T>
class SpscRing {
  static_assert(std::is_nothrow_copy_assignable_v<T> && std::is_default_constructible_v<T>,
                "SpscRing holds small copyable items (indices, handles, plain structs)");

 public:
  // Holds up to `capacity` items (at least 1).
  explicit SpscRing(std::size_t capacity)
      : size_(capacity + 1), slots_(std::make_unique<T[]>(capacity + 1)) {}
  SpscRing(const SpscRing&) = delete;
  SpscRing& operator=(const SpscRing&) = delete;

  // Producer only.
  [[nodiscard]] bool try_push(const T& value) noexcept {
    const std::size_t tail = tail_.load(std::memory_order_relaxed);
    const std::size_t next = tail + 1 == size_ ? 0 : tail + 1;
    if (next == head_cache_) {
      head_cache_ = head_.load(std::memory_order_acquire);
      if (next == head_cache_) return false;
    }
    slots_[tail] = value;
    tail_.store(next, std::memory_order_release);
    return true;
  }

  // Consumer only.
  [[nodiscard]] bool try_pop(T& out) noexcept {
    const std::size_t head = head_.load(std::memory_order_relaxed);
    if (head == tail_cache_) {
      tail_cache_ = tail_.load(std::memory_order_acquire);
      if (head == tail_cache_) return false;
    }
    out = slots_[head];
    head_.store(head + 1 == size_ ? 0 : head + 1, std::memory_order_release);
    return true;
  }

  // Either side; exact only when the other side is idle.
  [[nodiscard]] std::size_t size() const noexcept {
    const std::size_t head = head_.load(std::memory_order_acquire);
    const std::size_t tail = tail_.load(std::memory_order_acquire);
    return tail >= head ? tail - head : tail + size_ - head;
  }
  [[nodiscard]] bool empty() const noexcept { return size() == 0; }
  [[nodiscard]] std::size_t capacity() const noexcept { return size_ - 1; }

 private:
  const std::size_t size_;
  std::unique_ptr<T[]> slots_;
  alignas(kCacheLine) std::atomic<std::size_t> head_{0};  // written by the consumer
  alignas(kCacheLine) std::size_t tail_cache_ = 0;        // consumer's copy of tail_
  alignas(kCacheLine) std::atomic<std::size_t> tail_{0};  // written by the producer
  alignas(kCacheLine) std::size_t head_cache_ = 0;        // producer's copy of head_
};

}  // namespace stac::rt
