// The publishing edge (docs/dds.md): STAC's per-scan results as DDS samples. Created once at
// start-up (domain, participant, topics, writers, and every sample's storage at its IDL bound);
// each publish_*() converts plain inputs into that storage and writes it with one dds_write.
// Inputs beyond an IDL bound are refused with an error naming the field and the bound (nothing
// is written); a failed Cyclone call is an error carrying Cyclone's return-code text.
// Not thread-safe: one thread publishes. Perception never includes this header.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <string>

#include "dds/topics.hpp"
#include "rt/expected.hpp"

namespace stac::tracking {
struct Track;
}

namespace stac::dds {

struct Vec3 {
  double x = 0, y = 0, z = 0;
};
struct Point2 {
  float x = 0, y = 0;
};

// Per-scan header: the scan's time (its last packet, Unix ns) and its index since start-up.
struct ScanStamp {
  std::int64_t stamp_ns = 0;
  std::uint64_t scan_index = 0;
};

struct TrackedObjectIn {
  std::uint64_t object_id = 0;
  float existence_probability = 0;  // 0..1
  bool classified = false;          // false: classification[] = {unknown, 1}
  // The model's K class names (K <= 8, each at most 31 characters; must outlive the publish
  // call) and log odds: its K classes in its order, then background at [K] (default model: car,
  // pedestrian, bicyclist, background).
  std::span<const std::string> class_names;
  std::array<float, 9> class_log_odds{};
  std::uint32_t class_age = 0;                 // scans since the class took a segment
  Vec3 position, velocity;                     // world (m, m/s)
  std::array<float, 9> position_covariance{};  // x,y,z row-major (m^2)
  std::array<float, 9> velocity_covariance{};  // ((m/s)^2)
  Vec3 dimensions;                             // length, width, height (m)
  float yaw = 0;                               // rad
  std::span<const Point2> footprint;           // empty: the box's 4 corners are published
  std::uint32_t point_count = 0, age = 0;
  std::uint8_t state = 0;  // 0 tentative, 1 confirmed, 2 coasting
};

// A tracker's track as an object (the edge may read perception; perception never reads DDS).
// Covariance: x,y variance from position_std_m (its largest axis), velocity covariance zero;
// existence probability 1 for confirmed and coasting tracks, 0.5 for tentative ones; not
// classified (the caller sets classified and class_log_odds from the classification stage).
TrackedObjectIn to_tracked_object(const tracking::Track& track) noexcept;

struct SegmentIn {
  std::uint32_t segment_id = 0;
  Vec3 centroid, dimensions;  // world (m)
  float yaw = 0;              // rad
  std::uint32_t point_count = 0;
};

// LabeledPointIn::segment of a point in no published segment.
inline constexpr std::uint16_t kNoSegment = 0xFFFF;
// One return of the compact labeled point cloud (idl/stac.idl LabeledPoint, the same layout).
struct LabeledPointIn {
  std::int16_t x = 0, y = 0, z = 0;  // from the origin, in units of the resolution
  std::uint8_t intensity = 0;
  std::uint8_t label =
      0;  // 0 no object, 1 car, 2 pedestrian, 3 bicyclist, 4 background, 5 unclassified
  std::uint16_t segment = kNoSegment;  // its segment's segment_id on the segments topic
};
struct PointCloudIn {
  ScanStamp scan;
  Vec3 origin;               // world (m)
  float resolution = 0.01f;  // m per unit
  std::span<const LabeledPointIn> points;
};

struct EgoPoseIn {
  std::int64_t stamp_ns = 0;
  Vec3 position;                                  // world (m)
  std::array<double, 4> orientation{0, 0, 0, 1};  // quaternion x, y, z, w
  Vec3 velocity;                                  // world (m/s)
  float yaw_rate = 0;                             // rad/s
  std::uint8_t source = 0;                        // 0 none, 1 INS, 2 CAN
};

struct StageLatencyIn {
  const char* stage = "";  // at most 23 characters
  std::uint32_t latency_us = 0;
};
struct DropCountIn {
  const char* cause = "";  // at most 31 characters
  std::uint64_t count = 0;
};
struct SensorStatusIn {
  const char* name = "";    // at most 15 characters
  std::uint8_t status = 0;  // 0 ok, 1 stale, 2 error, 3 not configured
  float age_s = 0;
};
struct HealthIn {
  ScanStamp scan;
  std::span<const StageLatencyIn> stages;
  std::uint32_t end_to_end_latency_us = 0;
  std::uint64_t deadline_misses = 0;
  std::span<const DropCountIn> drops;
  std::span<const SensorStatusIn> sensors;
  std::uint64_t model_hash = 0;  // the classifier model in use (0: none)
  std::uint32_t model_reloads = 0;
};

struct PublisherConfig {
  std::uint32_t domain_id = 0;
  std::string topic_prefix = "stac";  // topics "<prefix>/tracked_objects", ...
  bool ros2_names = false;            // stac_msgs::msg::dds_::Name_ types, "rt/" topics
  std::string config_uri;         // Cyclone XML ("file://...") or empty: CYCLONEDDS_URI/defaults
  std::string frame_id = "map";   // frame_id of every sample, at most 31 characters
  bool tentative_tracks = false;  // publish tentative tracks too (not yet confirmed: mostly
                                  // clutter that lives a scan or two)
  std::uint32_t point_cloud_stride = 8;  // point_cloud: every return in a segment and every Nth
                                         // other one; 0: the topic is not published
};

class Publisher {
 public:
  // Creates the domain (with config_uri when given), participant, topics and writers.
  static rt::Result<std::unique_ptr<Publisher>> create(const PublisherConfig& config);
  virtual ~Publisher() = default;

  virtual rt::Status publish_tracked_objects(const ScanStamp& scan,
                                             std::span<const TrackedObjectIn> objects) = 0;
  virtual rt::Status publish_segments(const ScanStamp& scan,
                                      std::span<const SegmentIn> segments) = 0;
  virtual rt::Status publish_ego_pose(const EgoPoseIn& pose) = 0;
  virtual rt::Status publish_health(const HealthIn& health) = 0;
  virtual rt::Status publish_point_cloud(const PointCloudIn& cloud) = 0;

  // The writer of a topic (for status queries: matched readers, deadline misses).
  [[nodiscard]] virtual dds_entity_t writer(Topic t) const noexcept = 0;
  [[nodiscard]] virtual dds_entity_t participant() const noexcept = 0;
};

}  // namespace stac::dds
