#include "perception/tracking/track.hpp"

#include <algorithm>
#include <cmath>

#include "perception/tracking/shapes.hpp"

namespace stac::tracking {

const char* state_name(TrackState s) noexcept {
  switch (s) {
    case TrackState::kTentative:
      return "tentative";
    case TrackState::kConfirmed:
      return "confirmed";
    case TrackState::kCoasting:
      return "coasting";
  }
  return "unknown";
}

void HolisticFeatures::add_segment(const Eigen::Vector3f& centroid, std::int64_t stamp_ns,
                                   double min_heading_speed_mps) noexcept {
  ++segments_;
  centroids_[static_cast<std::size_t>(head_)] = centroid;
  stamps_[static_cast<std::size_t>(head_)] = stamp_ns;
  head_ = (head_ + 1) % kWindow;
  filled_ = std::min(filled_ + 1, kWindow);
  if (filled_ < 2) return;
  const auto newest = static_cast<std::size_t>((head_ + kWindow - 1) % kWindow);
  const auto oldest = static_cast<std::size_t>((head_ + kWindow - filled_) % kWindow);
  const double span_s = static_cast<double>(stamps_[newest] - stamps_[oldest]) * 1e-9;
  if (!(span_s > 0)) return;
  const Eigen::Vector2f v =
      ((centroids_[newest] - centroids_[oldest]).head<2>() / static_cast<float>(span_s)).eval();
  const float speed = v.norm();
  max_speed_ = std::max(max_speed_, speed);
  speed_sum_ += speed;
  ++speed_count_;
  if (have_velocity_) {
    const double dt = static_cast<double>(stamp_ns - velocity_stamp_) * 1e-9;
    if (dt > 0) {
      const auto accel = static_cast<float>((v - velocity_).norm() / dt);
      max_accel_ = std::max(max_accel_, accel);
      accel_sum_ += accel;
      ++accel_count_;
      if (speed >= min_heading_speed_mps && velocity_.norm() >= min_heading_speed_mps) {
        const double turn =
            shapes::wrap_pi(std::atan2(v.y(), v.x()) - std::atan2(velocity_.y(), velocity_.x()));
        max_angular_ = std::max(max_angular_, static_cast<float>(std::abs(turn) / dt));
      }
    }
  }
  velocity_ = v;
  velocity_stamp_ = stamp_ns;
  have_velocity_ = true;
}

float HolisticFeatures::mean_speed_mps() const noexcept {
  return speed_count_ == 0 ? 0.0f : static_cast<float>(speed_sum_ / speed_count_);
}

float HolisticFeatures::mean_accel_mps2() const noexcept {
  return accel_count_ == 0 ? 0.0f : static_cast<float>(accel_sum_ / accel_count_);
}

}  // namespace stac::tracking
