// What a track reports after each scan, and the running holistic features the classifier uses
// (thesis ch. 1: max/mean speed, max/mean acceleration, max angular velocity from a centroid
// velocity smoothed over 5 segments). Fixed size: running sums, never a list of frames.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>

namespace stac::tracking {

enum class TrackState : std::uint8_t {
  kTentative,  // fewer than life.confirm_hits hits so far
  kConfirmed,  // matched in this scan (and confirmed)
  kCoasting,   // confirmed, missed in this scan: position predicted only
};

const char* state_name(TrackState s) noexcept;  // "tentative", "confirmed", "coasting"

class HolisticFeatures {
 public:
  static constexpr int kWindow = 5;  // segments the centroid velocity is smoothed over

  // One associated segment: its centroid (world, m) and stamp (ns).
  void add_segment(const Eigen::Vector3f& centroid, std::int64_t stamp_ns,
                   double min_heading_speed_mps) noexcept;

  [[nodiscard]] std::uint32_t segment_count() const noexcept { return segments_; }
  // Smoothed x,y velocity (m/s) over the last kWindow segments; zero before the second segment.
  [[nodiscard]] Eigen::Vector2f smoothed_velocity() const noexcept { return velocity_; }
  [[nodiscard]] float max_speed_mps() const noexcept { return max_speed_; }
  [[nodiscard]] float mean_speed_mps() const noexcept;
  [[nodiscard]] float max_accel_mps2() const noexcept { return max_accel_; }
  [[nodiscard]] float mean_accel_mps2() const noexcept;
  [[nodiscard]] float max_angular_velocity_rps() const noexcept { return max_angular_; }

 private:
  std::array<Eigen::Vector3f, kWindow> centroids_{};
  std::array<std::int64_t, kWindow> stamps_{};
  int head_ = 0, filled_ = 0;
  std::uint32_t segments_ = 0;
  Eigen::Vector2f velocity_ = Eigen::Vector2f::Zero();
  std::int64_t velocity_stamp_ = 0;
  bool have_velocity_ = false;
  float max_speed_ = 0, max_accel_ = 0, max_angular_ = 0;
  double speed_sum_ = 0, accel_sum_ = 0;
  std::uint32_t speed_count_ = 0, accel_count_ = 0;
};

struct Track {
  std::uint64_t id = 0;    // stable for the track's life, never reused
  std::uint32_t slot = 0;  // the tracker's pool slot holding it (< max_tracks); reused by a
                           // later track once this one ends (per-track state elsewhere keys on it)
  TrackState state = TrackState::kTentative;
  Eigen::Vector3f position = Eigen::Vector3f::Zero();  // filtered centroid, world (m)
  Eigen::Vector2f velocity = Eigen::Vector2f::Zero();  // filtered x,y velocity (m/s)
  float position_std_m = 0;  // sqrt(max eigenvalue of the x,y position covariance)
  float length = 0, width = 0, height = 0, yaw = 0;  // smoothed box (m, rad)
  std::uint32_t points = 0;                          // points of the last associated detection
  std::int32_t segment = -1;  // Detection::segment matched in this scan, -1 when coasting
  std::uint32_t age = 0;      // scans since spawn (0 in the spawning scan)
  std::uint32_t hits = 0;     // associated detections so far
  std::uint32_t misses = 0;   // consecutive scans without one
  HolisticFeatures features;
};

}  // namespace stac::tracking
