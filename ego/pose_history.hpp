// The last seconds of vehicle poses (200 Hz from the INS, or dead reckoning), written by one
// thread and read by any number of threads without locks (ARCHITECTURE: PoseHistory).
//
//   writer:  history.push(sample);                 // strictly increasing stamps
//   readers: PoseLookup l = history.at(stamp_ns);  if (l.ok()) use(l.pose);
//
// Each slot is a seqlock of atomics: a reader that raced the writer retries, and a slot
// overwritten while it was read is detected by the sample index stored in its sequence. Readers
// never block the writer; the writer never waits. No allocation after construction.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <memory>

#include "ego/pose.hpp"

namespace stac::ego {

struct PoseHistoryConfig {
  std::size_t capacity = 2000;                     // samples kept (10 s at 200 Hz)
  std::int64_t max_extrapolation_ns = 50'000'000;  // beyond the newest sample, by its velocity
  std::int64_t max_gap_ns = 100'000'000;           // bracketing samples farther apart: a gap
};

enum class PoseStatus : std::uint8_t {
  kInterpolated,  // between two samples: linear position and velocity, slerp attitude
  kExtrapolated,  // after the newest sample, within max_extrapolation_ns (velocity, angular rate)
  kTooOld,        // before the oldest sample kept
  kTooNew,        // after the newest by more than max_extrapolation_ns
  kGap,           // the bracketing samples are more than max_gap_ns apart
  kEmpty,         // no sample yet
};
const char* to_string(PoseStatus s) noexcept;

struct PoseLookup {
  PoseStatus status = PoseStatus::kEmpty;
  PoseSample pose;
  [[nodiscard]] bool ok() const noexcept {
    return status == PoseStatus::kInterpolated || status == PoseStatus::kExtrapolated;
  }
};

class PoseHistory {
 public:
  explicit PoseHistory(const PoseHistoryConfig& config);

  // Writer thread only. False (and counted) when the stamp is not newer than the last one or
  // the sample is not finite.
  bool push(const PoseSample& sample) noexcept;
  // Writer thread only: starts a new timeline with `sample` (the clock went back: a looping
  // replay, a bad fix corrected). Lookups see only the samples from it on. False (and counted)
  // when the sample is not finite.
  bool restart(const PoseSample& sample) noexcept;

  // Any thread.
  [[nodiscard]] PoseLookup at(std::int64_t stamp_ns) const noexcept;
  [[nodiscard]] std::uint64_t pushed() const noexcept {
    return head_.load(std::memory_order_acquire);
  }
  [[nodiscard]] std::uint64_t rejected() const noexcept {
    return rejected_.load(std::memory_order_relaxed);
  }
  // The newest sample's stamp, or INT64_MIN when empty.
  [[nodiscard]] std::int64_t newest_stamp_ns() const noexcept;

 private:
  static constexpr int kFields = 16;  // position 3, attitude 4, velocity 3, angular rate 3, pad
  struct alignas(64) Slot {
    std::atomic<std::uint64_t> sequence{0};  // 2i+1 while sample i is written, 2i+2 when done
    std::atomic<std::int64_t> stamp_ns{0};
    std::array<std::atomic<double>, kFields> v{};
  };
  bool read(std::uint64_t index, PoseSample& out) const noexcept;
  bool read_stamp(std::uint64_t index, std::int64_t& out) const noexcept;

  PoseHistoryConfig config_;
  std::unique_ptr<Slot[]> slots_;
  alignas(64) std::atomic<std::uint64_t> head_{0};  // samples pushed
  std::atomic<std::uint64_t> first_{0};             // index of the current timeline's first sample
  std::atomic<std::uint64_t> rejected_{0};
  std::int64_t last_stamp_ns_ = 0;  // writer only
};

// Interpolates between two samples (t between their stamps; outside: clamped).
PoseSample interpolate(const PoseSample& a, const PoseSample& b, std::int64_t stamp_ns) noexcept;
// Moves a sample forward by its velocity and angular rate.
PoseSample extrapolate(const PoseSample& p, std::int64_t stamp_ns) noexcept;

}  // namespace stac::ego
