// Counters that one thread writes and any thread reads, named by an enum class whose last
// enumerator is kCount: the drops and events a live process publishes on its health topic.
// Relaxed atomics (a reader sees each counter's latest value, not a snapshot of all at one
// instant); fixed size, lock-free, no allocation.
#pragma once

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>

namespace stac::rt {

template <typename Id>
class Counters {
 public:
  static constexpr std::size_t kSize = static_cast<std::size_t>(Id::kCount);

  void add(Id id, std::uint64_t n = 1) noexcept {
    cells_[index(id)].fetch_add(n, std::memory_order_relaxed);
  }
  // The writer's own running total (e.g. a driver's counter copied after each read).
  void set(Id id, std::uint64_t value) noexcept {
    cells_[index(id)].store(value, std::memory_order_relaxed);
  }
  [[nodiscard]] std::uint64_t get(Id id) const noexcept {
    return cells_[index(id)].load(std::memory_order_relaxed);
  }

 private:
  static constexpr std::size_t index(Id id) noexcept { return static_cast<std::size_t>(id); }
  std::array<std::atomic<std::uint64_t>, kSize> cells_{};
};

}  // namespace stac::rt
