// A track's accumulated cloud in fixed memory (the thesis's holistic descriptors include the
// segment descriptors of it): every added segment is moved so its x,y centroid is at the origin
// (z kept: sensor frame, z up; no rotation, so a turning object smears), and at most `capacity`
// points are kept by reservoir sampling, so every point ever added has the same chance to be in
// the cloud. Deterministic for a seed. Allocates at construction only.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>

#include "perception/descriptors/descriptors.hpp"
#include "rt/splitmix64.hpp"

namespace stac::classification {

class AccumulatedCloud {
 public:
  explicit AccumulatedCloud(std::size_t capacity, std::uint64_t seed = 1);

  // Adds the segment's finite points (x, y, z, intensity). No allocation, exception or I/O.
  void add_segment(const descriptors::SegmentView& segment) noexcept;
  void clear() noexcept;                    // empty again, same seed sequence continues
  void clear(std::uint64_t seed) noexcept;  // empty again, sampling restarted from `seed`

  // The kept points (x, y, z, intensity; stride 16), valid until the next add_segment/clear.
  [[nodiscard]] descriptors::SegmentView view() const noexcept;
  [[nodiscard]] std::size_t size() const noexcept { return size_; }
  [[nodiscard]] std::size_t capacity() const noexcept { return capacity_; }
  [[nodiscard]] std::uint64_t points_seen() const noexcept { return seen_; }

 private:
  std::unique_ptr<float[]> xyzi_;
  std::size_t capacity_ = 0, size_ = 0;
  std::uint64_t seen_ = 0;
  rt::SplitMix64 rng_;
};

}  // namespace stac::classification
