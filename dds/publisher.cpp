#include "dds/publisher.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <string_view>
#include <vector>

#include "dds/domain.hpp"
#include "dds/idl_types.hpp"
#include "perception/tracking/track.hpp"

namespace stac::dds {
namespace {

using Status = rt::Status;

// The bounds above against the generated C types (the IDL is the source of truth).
static_assert(sizeof(stac_msgs_msg_TrackedObjects::frame_id) == 32);
static_assert(sizeof(stac_msgs_msg_StageLatency::stage) == 24);
static_assert(sizeof(stac_msgs_msg_DropCount::cause) == 32);
static_assert(sizeof(stac_msgs_msg_SensorStatus::name) == 16);
static_assert(sizeof(stac_msgs_msg_TrackedObject::class_log_odds) ==
              sizeof(TrackedObjectIn::class_log_odds));
static_assert(sizeof(stac_msgs_msg_ObjectClassification::name) == kMaxClassNameLength + 1);
static_assert(sizeof(stac_msgs_msg_TrackedObjects) == sizeof(stac_msgs_msg_dds__TrackedObjects_));
static_assert(sizeof(stac_msgs_msg_Health) == sizeof(stac_msgs_msg_dds__Health_));
// A point cloud is copied as it is: the input's layout is the IDL's.
static_assert(sizeof(LabeledPointIn) == sizeof(stac_msgs_msg_LabeledPoint) &&
              offsetof(LabeledPointIn, intensity) ==
                  offsetof(stac_msgs_msg_LabeledPoint, intensity) &&
              offsetof(LabeledPointIn, label) == offsetof(stac_msgs_msg_LabeledPoint, label) &&
              offsetof(LabeledPointIn, segment) == offsetof(stac_msgs_msg_LabeledPoint, segment));
static_assert(sizeof(stac_msgs_msg_LabeledPoint) == sizeof(stac_msgs_msg_dds__LabeledPoint_));

template <class Seq, class T>
void attach(Seq& seq, std::vector<T>& storage, std::size_t offset, std::uint32_t bound) {
  seq._maximum = bound;
  seq._length = 0;
  seq._buffer = storage.data() + offset;
  seq._release = false;
}

// Copies a C string into a bounded IDL string (char[N+1]); refuses what does not fit.
template <std::size_t N>
Status copy_string(char (&dst)[N], const char* src, const char* field) {
  const std::size_t len = src == nullptr ? 0 : strnlen(src, N);
  if (len >= N) {
    return rt::make_error(std::string(field) + " '" + src + "' is longer than its bound of " +
                          std::to_string(N - 1) + " characters (idl/stac.idl)");
  }
  std::memcpy(dst, src == nullptr ? "" : src, len);
  dst[len] = '\0';
  return {};
}

Status check_bound(std::size_t n, std::uint32_t bound, const char* field) {
  if (n <= bound) return {};
  return rt::make_error(std::string(field) + ": " + std::to_string(n) +
                        " elements exceed the bound of " + std::to_string(bound) +
                        " (idl/stac.idl); nothing was published");
}

template <class Time>
Status to_time(std::int64_t stamp_ns, Time& t) {
  std::int64_t sec = stamp_ns / 1'000'000'000;
  std::int64_t ns = stamp_ns % 1'000'000'000;
  if (ns < 0) {
    ns += 1'000'000'000;
    --sec;
  }
  if (sec < INT32_MIN || sec > INT32_MAX) {
    return rt::make_error("stamp " + std::to_string(stamp_ns) +
                          " ns does not fit ROS time (int32 s)");
  }
  t.sec = static_cast<std::int32_t>(sec);
  t.nanosec = static_cast<std::uint32_t>(ns);
  return {};
}

// Copies a name into a bounded IDL string, cut at its bound (class names are checked to fit when
// a model loads).
template <std::size_t N>
void copy_name(char (&dst)[N], std::string_view name) noexcept {
  const std::size_t len = std::min(name.size(), N - 1);
  std::memcpy(dst, name.data(), len);
  dst[len] = '\0';
}

template <class V>
void set(V& v, const Vec3& in) {
  v.x = in.x;
  v.y = in.y;
  v.z = in.z;
}

// Writers for one naming mode; the samples and every sequence's buffer live here.
template <bool Ros2>
class TypedPublisher final : public Publisher {
  using T = IdlTypes<Ros2>;

 public:
  TypedPublisher(const PublisherConfig& config, dds_entity_t domain, dds_entity_t participant)
      : config_(config),
        domain_(domain),
        participant_(participant),
        objects_(kMaxObjects),
        classifications_(kMaxObjects * kMaxClassifications),
        footprints_(kMaxObjects * kMaxFootprint),
        segment_items_(kMaxSegments),
        stages_(kMaxStages),
        drops_(kMaxDrops),
        sensors_(kMaxSensors),
        cloud_points_(kMaxCloudPoints) {
    attach(tracked_.objects, objects_, 0, kMaxObjects);
    for (std::size_t i = 0; i < kMaxObjects; ++i) {
      attach(objects_[i].classification, classifications_, i * kMaxClassifications,
             kMaxClassifications);
      attach(objects_[i].shape.footprint, footprints_, i * kMaxFootprint, kMaxFootprint);
    }
    attach(segments_.segments, segment_items_, 0, kMaxSegments);
    attach(health_.stages, stages_, 0, kMaxStages);
    attach(health_.drops, drops_, 0, kMaxDrops);
    attach(health_.sensors, sensors_, 0, kMaxSensors);
    attach(cloud_.points, cloud_points_, 0, kMaxCloudPoints);
  }
  ~TypedPublisher() override {
    dds_delete(participant_);
    if (domain_ > 0) dds_delete(domain_);
  }

  Status init() {
    if (auto s = copy_string(tracked_.frame_id, config_.frame_id.c_str(), "dds frame_id"); !s)
      return s;
    std::memcpy(segments_.frame_id, tracked_.frame_id, sizeof(tracked_.frame_id));
    std::memcpy(pose_.frame_id, tracked_.frame_id, sizeof(tracked_.frame_id));
    std::memcpy(cloud_.frame_id, tracked_.frame_id, sizeof(tracked_.frame_id));
    const dds_topic_descriptor_t* descriptors[] = {T::tracked_objects(), T::segments(),
                                                   T::ego_pose(), T::health(), T::point_cloud()};
    static_assert(std::size(descriptors) == std::size(kAllTopics));
    for (Topic t : kAllTopics) {
      const auto i = static_cast<std::size_t>(t);
      const std::string name = topic_name(t, config_.topic_prefix, config_.ros2_names);
      const dds_entity_t topic =
          dds_create_topic(participant_, descriptors[i], name.c_str(), nullptr, nullptr);
      if (topic < 0) return dds_error("creating DDS topic '" + name + "'", topic);
      writers_[i] = dds_create_writer(participant_, topic, writer_qos(t).get(), nullptr);
      if (writers_[i] < 0)
        return dds_error("creating the DDS writer of '" + name + "'", writers_[i]);
    }
    return {};
  }

  Status publish_tracked_objects(const ScanStamp& scan,
                                 std::span<const TrackedObjectIn> in) override {
    if (auto s = check_bound(in.size(), kMaxObjects, "tracked objects"); !s) return s;
    for (const TrackedObjectIn& o : in) {
      if (auto s = check_bound(o.footprint.size(), kMaxFootprint, "tracked object footprint"); !s)
        return s;
    }
    if (auto s = to_time(scan.stamp_ns, tracked_.stamp); !s) return s;
    tracked_.scan_index = scan.scan_index;
    tracked_.objects._length = static_cast<std::uint32_t>(in.size());
    for (std::size_t i = 0; i < in.size(); ++i) fill(objects_[i], in[i]);
    return write(Topic::kTrackedObjects, &tracked_);
  }

  Status publish_segments(const ScanStamp& scan, std::span<const SegmentIn> in) override {
    if (auto s = check_bound(in.size(), kMaxSegments, "segments"); !s) return s;
    if (auto s = to_time(scan.stamp_ns, segments_.stamp); !s) return s;
    segments_.scan_index = scan.scan_index;
    segments_.segments._length = static_cast<std::uint32_t>(in.size());
    for (std::size_t i = 0; i < in.size(); ++i) {
      auto& d = segment_items_[i];
      d.segment_id = in[i].segment_id;
      set(d.centroid, in[i].centroid);
      set(d.dimensions, in[i].dimensions);
      d.yaw = in[i].yaw;
      d.point_count = in[i].point_count;
    }
    return write(Topic::kSegments, &segments_);
  }

  Status publish_ego_pose(const EgoPoseIn& in) override {
    if (auto s = to_time(in.stamp_ns, pose_.stamp); !s) return s;
    set(pose_.position, in.position);
    std::copy(in.orientation.begin(), in.orientation.end(), pose_.orientation);
    set(pose_.velocity, in.velocity);
    pose_.yaw_rate = in.yaw_rate;
    pose_.source = in.source;
    return write(Topic::kEgoPose, &pose_);
  }

  Status publish_health(const HealthIn& in) override {
    if (auto s = check_bound(in.stages.size(), kMaxStages, "health stages"); !s) return s;
    if (auto s = check_bound(in.drops.size(), kMaxDrops, "health drops"); !s) return s;
    if (auto s = check_bound(in.sensors.size(), kMaxSensors, "health sensors"); !s) return s;
    for (std::size_t i = 0; i < in.stages.size(); ++i) {
      if (auto s = copy_string(stages_[i].stage, in.stages[i].stage, "health stage"); !s) return s;
      stages_[i].latency_us = in.stages[i].latency_us;
    }
    for (std::size_t i = 0; i < in.drops.size(); ++i) {
      if (auto s = copy_string(drops_[i].cause, in.drops[i].cause, "health drop cause"); !s)
        return s;
      drops_[i].count = in.drops[i].count;
    }
    for (std::size_t i = 0; i < in.sensors.size(); ++i) {
      if (auto s = copy_string(sensors_[i].name, in.sensors[i].name, "health sensor name"); !s)
        return s;
      sensors_[i].status = in.sensors[i].status;
      sensors_[i].age_s = in.sensors[i].age_s;
    }
    if (auto s = to_time(in.scan.stamp_ns, health_.stamp); !s) return s;
    health_.scan_index = in.scan.scan_index;
    health_.stages._length = static_cast<std::uint32_t>(in.stages.size());
    health_.drops._length = static_cast<std::uint32_t>(in.drops.size());
    health_.sensors._length = static_cast<std::uint32_t>(in.sensors.size());
    health_.end_to_end_latency_us = in.end_to_end_latency_us;
    health_.deadline_misses = in.deadline_misses;
    health_.model_hash = in.model_hash;
    health_.model_reloads = in.model_reloads;
    return write(Topic::kHealth, &health_);
  }

  Status publish_point_cloud(const PointCloudIn& in) override {
    if (auto s = check_bound(in.points.size(), kMaxCloudPoints, "point cloud points"); !s) return s;
    if (auto s = to_time(in.scan.stamp_ns, cloud_.stamp); !s) return s;
    cloud_.scan_index = in.scan.scan_index;
    set(cloud_.origin, in.origin);
    cloud_.resolution = in.resolution;
    if (!in.points.empty())
      std::memcpy(cloud_points_.data(), in.points.data(),
                  in.points.size() * sizeof(LabeledPointIn));
    cloud_.points._length = static_cast<std::uint32_t>(in.points.size());
    return write(Topic::kPointCloud, &cloud_);
  }

  dds_entity_t writer(Topic t) const noexcept override {
    return writers_[static_cast<std::size_t>(t)];
  }
  dds_entity_t participant() const noexcept override { return participant_; }

 private:
  void fill(typename T::TrackedObject& d, const TrackedObjectIn& o) {
    d.object_id = o.object_id;
    d.existence_probability = o.existence_probability;
    std::copy(o.class_log_odds.begin(), o.class_log_odds.end(), d.class_log_odds);
    d.class_age = o.class_age;
    // classification[]: every class of the model and background with its probability (logistic
    // of its log odds), most probable first; labels 1..K the model's classes, K + 1 background
    // (default model: 1 car, 2 pedestrian, 3 bicyclist, 4 background), each with its name.
    // Unclassified: one entry, label 0 (unknown), probability 1.
    auto* c = d.classification._buffer;
    const std::size_t classes =
        std::min<std::size_t>(o.class_names.size(), kMaxClassifications - 1);
    if (o.classified) {
      for (std::size_t k = 0; k <= classes; ++k) {
        c[k].label = static_cast<std::uint8_t>(k + 1);
        c[k].probability = 1.0f / (1.0f + std::exp(-o.class_log_odds[k]));
        copy_name(c[k].name, k < classes ? std::string_view(o.class_names[k]) : "background");
      }
      for (std::size_t k = 1; k <= classes; ++k) {  // insertion sort: stable, never allocates
        for (std::size_t j = k; j > 0 && c[j].probability > c[j - 1].probability; --j)
          std::swap(c[j], c[j - 1]);
      }
      d.classification._length = static_cast<std::uint32_t>(classes + 1);
    } else {
      c[0].label = 0;
      c[0].probability = 1.0f;
      copy_name(c[0].name, "unknown");
      d.classification._length = 1;
    }
    set(d.kinematics.position, o.position);
    set(d.kinematics.velocity, o.velocity);
    std::copy(o.position_covariance.begin(), o.position_covariance.end(),
              d.kinematics.position_covariance);
    std::copy(o.velocity_covariance.begin(), o.velocity_covariance.end(),
              d.kinematics.velocity_covariance);
    set(d.shape.dimensions, o.dimensions);
    d.shape.yaw = o.yaw;
    auto* f = d.shape.footprint._buffer;
    if (o.footprint
            .empty()) {  // the box: corners counter-clockwise from front-left... of length x width
      const double c0 = std::cos(o.yaw), s0 = std::sin(o.yaw);
      const double hl = o.dimensions.x / 2, hw = o.dimensions.y / 2;
      const double corners[4][2] = {{hl, hw}, {-hl, hw}, {-hl, -hw}, {hl, -hw}};
      for (int k = 0; k < 4; ++k) {
        f[k].x = static_cast<float>(o.position.x + c0 * corners[k][0] - s0 * corners[k][1]);
        f[k].y = static_cast<float>(o.position.y + s0 * corners[k][0] + c0 * corners[k][1]);
      }
      d.shape.footprint._length = 4;
    } else {
      for (std::size_t k = 0; k < o.footprint.size(); ++k) {
        f[k].x = o.footprint[k].x;
        f[k].y = o.footprint[k].y;
      }
      d.shape.footprint._length = static_cast<std::uint32_t>(o.footprint.size());
    }
    d.point_count = o.point_count;
    d.age = o.age;
    d.state = o.state;
  }

  Status write(Topic t, const void* sample) {
    const dds_return_t rc = dds_write(writer(t), sample);
    if (rc < 0) return dds_error(std::string("writing DDS topic ") + topic_suffix(t), rc);
    return {};
  }

  PublisherConfig config_;
  dds_entity_t domain_, participant_;
  std::array<dds_entity_t, std::size(kAllTopics)> writers_{};
  typename T::TrackedObjects tracked_{};
  std::vector<typename T::TrackedObject> objects_;
  std::vector<typename T::ObjectClassification> classifications_;
  std::vector<typename T::Point2> footprints_;
  typename T::ScanSegments segments_{};
  std::vector<typename T::Segment> segment_items_;
  typename T::EgoPose pose_{};
  typename T::Health health_{};
  std::vector<typename T::StageLatency> stages_;
  std::vector<typename T::DropCount> drops_;
  std::vector<typename T::SensorStatus> sensors_;
  typename T::LabeledPointCloud cloud_{};
  std::vector<typename T::LabeledPoint> cloud_points_;
};

template <bool Ros2>
rt::Result<std::unique_ptr<Publisher>> make(const PublisherConfig& config) {
  auto made = create_domain(config, ExistingDomain::kRefuse);
  if (!made) return rt::Unexpected<rt::Error>{made.error()};
  const dds_entity_t domain = *made;
  const dds_entity_t participant = dds_create_participant(config.domain_id, nullptr, nullptr);
  if (participant < 0) {
    if (domain > 0) dds_delete(domain);
    return dds_error("creating a DDS participant on domain " + std::to_string(config.domain_id),
                     participant);
  }
  auto p = std::make_unique<TypedPublisher<Ros2>>(config, domain, participant);
  if (auto s = p->init(); !s) return rt::Unexpected<rt::Error>{s.error()};
  return std::unique_ptr<Publisher>(std::move(p));
}

}  // namespace

rt::Result<std::unique_ptr<Publisher>> Publisher::create(const PublisherConfig& config) {
  if (config.domain_id > 230)
    return rt::make_error("dds domain id " + std::to_string(config.domain_id) + " must be 0..230");
  if (config.topic_prefix.empty()) return rt::make_error("dds topic prefix must not be empty");
  return config.ros2_names ? make<true>(config) : make<false>(config);
}

TrackedObjectIn to_tracked_object(const tracking::Track& track) noexcept {
  TrackedObjectIn o;
  o.object_id = track.id;
  o.existence_probability = track.state == tracking::TrackState::kTentative ? 0.5f : 1.0f;
  o.position = {track.position.x(), track.position.y(), track.position.z()};
  o.velocity = {track.velocity.x(), track.velocity.y(), 0.0};
  const float var = track.position_std_m * track.position_std_m;
  o.position_covariance[0] = var;
  o.position_covariance[4] = var;
  o.dimensions = {track.length, track.width, track.height};
  o.yaw = track.yaw;
  o.point_count = track.points;
  o.age = track.age;
  o.state = static_cast<std::uint8_t>(track.state);
  return o;
}

}  // namespace stac::dds
