#include "rt/watchdog.hpp"

namespace stac::rt {

const char* to_string(InputState s) noexcept {
  switch (s) {
    case InputState::kOk:
      return "ok";
    case InputState::kStalled:
      return "stalled";
    case InputState::kLost:
      return "lost";
    case InputState::kNotConfigured:
      return "not configured";
  }
  return "?";
}

void Watchdog::start(const std::array<std::int64_t, kMaxInputs>& timeouts_ns,
                     std::int64_t start_ns) noexcept {
  timeouts_ns_ = timeouts_ns;
  start_ns_ = start_ns;
  for (std::size_t i = 0; i < kMaxInputs; ++i) {
    last_ns_[i].store(kNever, std::memory_order_relaxed);
    lost_[i].store(false, std::memory_order_relaxed);
    was_stalled_[i] = false;
    stalls_[i] = 0;
  }
}

InputStatus Watchdog::status(std::size_t i, std::int64_t now_ns) const noexcept {
  if (i >= kMaxInputs || timeouts_ns_[i] <= 0) return {};
  const std::int64_t last = last_ns_[i].load(std::memory_order_relaxed);
  InputStatus s;
  s.seen = last != kNever;
  s.age_ns = now_ns - (s.seen ? last : start_ns_);
  if (lost_[i].load(std::memory_order_relaxed)) {
    s.state = InputState::kLost;
  } else {
    s.state = s.age_ns > timeouts_ns_[i] ? InputState::kStalled : InputState::kOk;
  }
  return s;
}

void Watchdog::update(std::int64_t now_ns) noexcept {
  for (std::size_t i = 0; i < kMaxInputs; ++i) {
    const InputState state = status(i, now_ns).state;
    const bool stalled = state == InputState::kStalled || state == InputState::kLost;
    if (stalled && !was_stalled_[i]) ++stalls_[i];
    was_stalled_[i] = stalled;
  }
}

}  // namespace stac::rt
