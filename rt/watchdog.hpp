// Stalled-input detection for a live process: each input (Velodyne, INS, CAN, ...) has a timeout;
// its reader thread calls beat() whenever good data arrives, and any thread asks status(). An
// input is stalled when it was seen once and then stayed silent longer than its timeout, or was
// never seen at all within its timeout of start(). An input whose reader gave up (the device or
// interface went away) is marked lost and stays lost until start(). update() (one checking
// thread) counts every transition into a stall or a loss. Fixed size, lock-free (atomics per
// input), no allocation.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>

namespace stac::rt {

enum class InputState : std::uint8_t {
  kOk,             // seen within its timeout
  kStalled,        // silent longer than its timeout
  kLost,           // its reader gave up: the device or interface is gone (lose())
  kNotConfigured,  // not part of this run
};
const char* to_string(InputState s) noexcept;

struct InputStatus {
  InputState state = InputState::kNotConfigured;
  bool seen = false;        // at least one beat since start()
  std::int64_t age_ns = 0;  // since the last beat (since start() when never seen)
};

class Watchdog {
 public:
  static constexpr std::size_t kMaxInputs = 4;

  // Input i is watched when timeouts_ns[i] > 0. `start_ns` is the clock's now (monotonic).
  void start(const std::array<std::int64_t, kMaxInputs>& timeouts_ns,
             std::int64_t start_ns) noexcept;

  // Reader threads: input i had good data at now_ns.
  void beat(std::size_t i, std::int64_t now_ns) noexcept {
    last_ns_[i].store(now_ns, std::memory_order_relaxed);
  }
  // Reader threads: input i is gone for good; status() says kLost from now on, beats or not.
  void lose(std::size_t i) noexcept { lost_[i].store(true, std::memory_order_relaxed); }

  [[nodiscard]] InputStatus status(std::size_t i, std::int64_t now_ns) const noexcept;
  // The checking thread: counts inputs that became stalled or lost since its previous call.
  void update(std::int64_t now_ns) noexcept;
  [[nodiscard]] std::uint64_t stalls(std::size_t i) const noexcept { return stalls_[i]; }

 private:
  static constexpr std::int64_t kNever = INT64_MIN;
  std::array<std::int64_t, kMaxInputs> timeouts_ns_{};
  std::int64_t start_ns_ = 0;
  std::array<std::atomic<std::int64_t>, kMaxInputs> last_ns_{};
  std::array<std::atomic<bool>, kMaxInputs> lost_{};
  std::array<bool, kMaxInputs> was_stalled_{};
  std::array<std::uint64_t, kMaxInputs> stalls_{};
};

}  // namespace stac::rt
