// Test helper: counts heap allocations (malloc family and operator new) made inside a region, in
// every thread, so a test can assert "0 allocations here" (osrf memory_tools style).
//
//   AllocationCounter counter;      // starts counting
//   ... steady-state code ...
//   counter.stop();
//   EXPECT_EQ(counter.allocations(), 0u);
//
// Link the target with stac_alloc_counter. In plain builds malloc, calloc, realloc and the
// aligned variants are interposed (operator new reaches them through libstdc++); under a
// sanitizer, which owns malloc, only operator new is counted (interposed() says which).
#pragma once

#include <cstdint>

namespace stac::rt::testing {

class AllocationCounter {
 public:
  AllocationCounter() noexcept;
  AllocationCounter(const AllocationCounter&) = delete;
  AllocationCounter& operator=(const AllocationCounter&) = delete;

  void stop() noexcept;
  // Allocations and bytes requested between construction and stop() (or now, if running).
  [[nodiscard]] std::uint64_t allocations() const noexcept;
  [[nodiscard]] std::uint64_t bytes() const noexcept;
  // True when the malloc family is counted; false under a sanitizer (operator new only).
  [[nodiscard]] static bool interposed() noexcept;

 private:
  std::uint64_t start_allocations_;
  std::uint64_t start_bytes_;
  std::uint64_t stop_allocations_ = 0;
  std::uint64_t stop_bytes_ = 0;
  bool running_ = true;
};

}  // namespace stac::rt::testing
