// Hands large preallocated objects (scan slots, result frames) from one producer thread to one
// consumer thread without copying or allocating: two SpscRings of slot indices, one carrying
// filled slots forward and one returning free slots.
//
//   producer: T& s = x.current(); fill s; x.publish();   // publish() moves on to a free slot
//   consumer: if (T* s = x.take()) { use *s; x.release(); }
//
// Full policy: drop newest. When the consumer still holds every other slot, publish() keeps the
// producer on the same slot (its content is overwritten by the next fill) and counts a drop; the
// slots the consumer has not taken yet are never touched.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "rt/spsc_ring.hpp"

namespace stac::rt {

template <class T>
class SlotExchange {
 public:
  // `slots` >= 2 objects, each made by `make()` now, at start-up.
  SlotExchange(std::size_t slots, const std::function<T()>& make) : full_(slots), free_(slots) {
    storage_.reserve(slots);
    for (std::size_t i = 0; i < slots; ++i) storage_.push_back(std::make_unique<T>(make()));
    for (std::uint32_t i = 1; i < slots; ++i) (void)free_.try_push(i);
  }

  // Producer: the slot being filled.
  T& current() noexcept { return *storage_[producing_]; }
  // Producer: hands the current slot to the consumer and moves to a free one. Returns false,
  // counting a drop, when no slot is free: the current slot is then reused.
  bool publish() noexcept {
    std::uint32_t next = 0;
    if (!free_.try_pop(next)) {
      dropped_.fetch_add(1, std::memory_order_relaxed);
      return false;
    }
    (void)full_.try_push(producing_);  // cannot fail: at most slots-1 indices are in flight
    producing_ = next;
    published_.fetch_add(1, std::memory_order_relaxed);
    return true;
  }

  // Consumer: the oldest published slot, or nullptr. The slot stays the consumer's until
  // release(); take() again before release() returns the same slot.
  T* take() noexcept {
    if (!holding_) {
      if (!full_.try_pop(consuming_)) return nullptr;
      holding_ = true;
    }
    return storage_[consuming_].get();
  }
  // Consumer: gives the taken slot back to the producer.
  void release() noexcept {
    if (!holding_) return;
    (void)free_.try_push(consuming_);
    holding_ = false;
  }

  [[nodiscard]] std::uint64_t published() const noexcept {
    return published_.load(std::memory_order_relaxed);
  }
  [[nodiscard]] std::uint64_t dropped() const noexcept {
    return dropped_.load(std::memory_order_relaxed);
  }
  [[nodiscard]] std::size_t slots() const noexcept { return storage_.size(); }

 private:
  std::vector<std::unique_ptr<T>> storage_;
  SpscRing<std::uint32_t> full_;  // producer -> consumer
  SpscRing<std::uint32_t> free_;  // consumer -> producer
  std::uint32_t producing_ = 0;   // producer's slot
  std::uint32_t consuming_ = 0;   // consumer's slot while holding_
  bool holding_ = false;
  std::atomic<std::uint64_t> published_{0};
  std::atomic<std::uint64_t> dropped_{0};
};

}  // namespace stac::rt
