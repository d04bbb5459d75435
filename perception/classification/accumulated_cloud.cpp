#include "perception/classification/accumulated_cloud.hpp"

#include <cmath>
#include <cstring>

namespace stac::classification {
namespace {

bool finite(const float (&p)[4]) noexcept {
  return std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]) && std::isfinite(p[3]);
}

}  // namespace

AccumulatedCloud::AccumulatedCloud(std::size_t capacity, std::uint64_t seed)
    : xyzi_(std::make_unique<float[]>(capacity * 4)), capacity_(capacity), rng_(seed) {}

void AccumulatedCloud::add_segment(const descriptors::SegmentView& segment) noexcept {
  double cx = 0, cy = 0;
  std::size_t n = 0;
  float p[4];
  for (std::size_t k = 0; k < segment.size(); ++k) {
    segment.read(k, p);
    if (!finite(p)) continue;
    cx += p[0];
    cy += p[1];
    ++n;
  }
  if (n == 0 || capacity_ == 0) return;
  cx /= static_cast<double>(n);
  cy /= static_cast<double>(n);
  for (std::size_t k = 0; k < segment.size(); ++k) {
    segment.read(k, p);
    if (!finite(p)) continue;
    p[0] = static_cast<float>(p[0] - cx);
    p[1] = static_cast<float>(p[1] - cy);
    std::size_t slot = size_;
    if (size_ == capacity_) {  // reservoir: keep the new point with probability capacity/seen
      slot = static_cast<std::size_t>(rng_.next() % (seen_ + 1));
      if (slot >= capacity_) slot = capacity_;
    } else {
      ++size_;
    }
    ++seen_;
    if (slot < capacity_) std::memcpy(xyzi_.get() + 4 * slot, p, sizeof(p));
  }
}

void AccumulatedCloud::clear() noexcept {
  size_ = 0;
  seen_ = 0;
}

void AccumulatedCloud::clear(std::uint64_t seed) noexcept {
  clear();
  rng_ = rt::SplitMix64(seed);
}

descriptors::SegmentView AccumulatedCloud::view() const noexcept {
  descriptors::SegmentView v;
  v.xyzi = xyzi_.get();
  v.stride_bytes = 4 * sizeof(float);
  v.count = size_;
  return v;
}

}  // namespace stac::classification
