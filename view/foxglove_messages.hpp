// STAC's DDS samples as Foxglove messages (JSON, docs/view.md): the labelled point cloud as a
// foxglove.PointCloud (x, y, z, intensity, label and a colour per class), the tracked objects as a
// foxglove.SceneUpdate (a box coloured by class, "#id class speed" above it, a velocity arrow and
// the path it came along), the ego pose as a foxglove.FrameTransform (map -> base_link) and the
// health as stac.Health. Templates over the sample types of either naming mode (dds::IdlTypes).
#pragma once

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <deque>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <string_view>

#include "dds/publisher.hpp"
#include "dds/reading.hpp"

namespace stac::view {

// The JSON schemas of the four channels (foxglove_messages.cpp).
extern const char* const kPointCloudSchema;
extern const char* const kSceneUpdateSchema;
extern const char* const kFrameTransformSchema;
extern const char* const kHealthSchema;

// Standard base64 of `bytes` (the PointCloud's data field).
std::string base64(std::string_view bytes);

struct Rgba {
  double r, g, b, a;
};
// The colour of a class name: car blue, pedestrian red, bicyclist green, background grey,
// unknown white, any other class of a taught model yellow.
Rgba class_color(std::string_view name) noexcept;
// The colour of a point's segment (its segment_id; dds::kNoSegment: in none, dark grey): one of
// twelve distinct colours, consecutive ids five apart, so that neighbouring segments differ.
Rgba segment_color(std::uint16_t segment) noexcept;

// One point of the PointCloud's data: 20 bytes (x y z float32, intensity, label, red, green, blue,
// alpha uint8, segment uint16).
inline constexpr std::uint32_t kPointStride = 20;

template <class Time>
nlohmann::json stamp(const Time& t) {
  return {{"sec", t.sec < 0 ? 0 : t.sec}, {"nsec", t.nanosec}};
}
template <class Time>
std::uint64_t stamp_ns(const Time& t) noexcept {
  return t.sec < 0 ? 0 : static_cast<std::uint64_t>(t.sec) * 1'000'000'000ull + t.nanosec;
}

inline nlohmann::json xyz(double x, double y, double z) {
  return {{"x", x}, {"y", y}, {"z", z}};
}
inline nlohmann::json color(const Rgba& c) {
  return {{"r", c.r}, {"g", c.g}, {"b", c.b}, {"a", c.a}};
}
// A pose at (x, y, z) turned by `yaw` about z.
inline nlohmann::json pose(double x, double y, double z, double yaw) {
  return {{"position", xyz(x, y, z)},
          {"orientation",
           {{"x", 0.0}, {"y", 0.0}, {"z", std::sin(yaw / 2)}, {"w", std::cos(yaw / 2)}}}};
}

// foxglove.PointCloud of a labelled cloud: points relative to the sample's origin (the pose), in
// the world frame's axes.
template <class Cloud>
nlohmann::json point_cloud_message(const Cloud& c) {
  std::string data(std::size_t{c.points._length} * kPointStride, '\0');
  for (std::uint32_t i = 0; i < c.points._length; ++i) {
    const auto& p = c.points._buffer[i];
    char* out = data.data() + std::size_t{i} * kPointStride;
    const float v[3] = {static_cast<float>(p.x) * c.resolution,
                        static_cast<float>(p.y) * c.resolution,
                        static_cast<float>(p.z) * c.resolution};
    std::memcpy(out, v, sizeof v);
    const Rgba k = segment_color(p.segment);
    const std::uint8_t tail[6] = {p.intensity,
                                  p.label,
                                  static_cast<std::uint8_t>(std::lround(k.r * 255)),
                                  static_cast<std::uint8_t>(std::lround(k.g * 255)),
                                  static_cast<std::uint8_t>(std::lround(k.b * 255)),
                                  255};
    std::memcpy(out + 12, tail, sizeof tail);
    const std::uint16_t segment = p.segment;
    std::memcpy(out + 18, &segment, sizeof segment);
  }
  // PackedElementField types: 1 UINT8, 3 UINT16, 7 FLOAT32.
  const auto field = [](const char* name, int offset, int type) {
    return nlohmann::json{{"name", name}, {"offset", offset}, {"type", type}};
  };
  return {{"timestamp", stamp(c.stamp)},
          {"frame_id", c.frame_id},
          {"pose", pose(c.origin.x, c.origin.y, c.origin.z, 0.0)},
          {"point_stride", kPointStride},
          {"fields",
           {field("x", 0, 7), field("y", 4, 7), field("z", 8, 7), field("intensity", 12, 1),
            field("label", 13, 1), field("red", 14, 1), field("green", 15, 1), field("blue", 16, 1),
            field("alpha", 17, 1), field("segment", 18, 3)}},
          {"data", base64(data)},
          {"scan_index", c.scan_index}};
}

// The paths of the tracks seen: each track's last kMaxPathPoints box centres. A track missing
// from a sample is forgotten.
class TrackPaths {
 public:
  static constexpr std::size_t kMaxPathPoints = 100;
  template <class Objects>
  void update(const Objects& s) {
    std::set<std::uint64_t> seen;
    for (std::uint32_t i = 0; i < s.objects._length; ++i) {
      const auto& o = s.objects._buffer[i];
      auto& path = paths_[o.object_id];
      path.push_back({o.kinematics.position.x, o.kinematics.position.y, o.kinematics.position.z});
      if (path.size() > kMaxPathPoints) path.pop_front();
      seen.insert(o.object_id);
    }
    std::erase_if(paths_, [&](const auto& kv) { return seen.count(kv.first) == 0; });
  }
  struct Point {
    double x, y, z;
  };
  [[nodiscard]] const std::deque<Point>& path(std::uint64_t id) const { return paths_.at(id); }

 private:
  std::map<std::uint64_t, std::deque<Point>> paths_;
};

// foxglove.SceneUpdate of a tracked objects sample: all earlier entities deleted, one entity per
// object (id "track/<object_id>", in the sample's order) with its metadata (id, class,
// probability, speed, state, scan).
template <class Objects>
nlohmann::json scene_update_message(const Objects& s, const TrackPaths& paths) {
  nlohmann::json entities = nlohmann::json::array();
  for (std::uint32_t i = 0; i < s.objects._length; ++i) {
    const auto& o = s.objects._buffer[i];
    const auto& k = o.kinematics;
    const dds::ShownClass shown = dds::shown_class(o);
    const Rgba c = class_color(shown.name);
    const double speed = std::hypot(k.velocity.x, k.velocity.y);
    const double yaw = static_cast<double>(o.shape.yaw);
    const double top = k.position.z + o.shape.dimensions.z / 2;
    char text[96];
    std::snprintf(text, sizeof text, "#%llu %s %.1f m/s",
                  static_cast<unsigned long long>(o.object_id), shown.name, speed);
    nlohmann::json arrows = nlohmann::json::array();
    if (speed > 0.3) {
      arrows.push_back(
          {{"pose", pose(k.position.x, k.position.y, top, std::atan2(k.velocity.y, k.velocity.x))},
           {"shaft_length", speed},  // one second ahead
           {"shaft_diameter", 0.1},
           {"head_length", 0.4},
           {"head_diameter", 0.3},
           {"color", color(c)}});
    }
    nlohmann::json points = nlohmann::json::array();
    for (const TrackPaths::Point& p : paths.path(o.object_id)) points.push_back(xyz(p.x, p.y, p.z));
    Rgba faint = c;
    faint.a = 0.35;
    entities.push_back(
        {{"timestamp", stamp(s.stamp)},
         {"frame_id", s.frame_id},
         {"id", "track/" + std::to_string(o.object_id)},
         {"lifetime", {{"sec", 0}, {"nsec", 0}}},
         {"frame_locked", false},
         {"metadata",
          {{{"key", "object_id"}, {"value", std::to_string(o.object_id)}},
           {{"key", "class"}, {"value", shown.name}},
           {{"key", "probability"}, {"value", std::to_string(shown.probability)}},
           {{"key", "speed_mps"}, {"value", std::to_string(speed)}},
           {{"key", "state"}, {"value", std::to_string(o.state)}},
           {{"key", "scan"}, {"value", std::to_string(s.scan_index)}}}},
         {"arrows", arrows},
         {"cubes",
          {{{"pose", pose(k.position.x, k.position.y, k.position.z, yaw)},
            {"size", xyz(o.shape.dimensions.x, o.shape.dimensions.y, o.shape.dimensions.z)},
            {"color", color(faint)}}}},
         {"spheres", nlohmann::json::array()},
         {"cylinders", nlohmann::json::array()},
         {"lines",
          {{{"type", 0},  // LINE_STRIP
            {"pose", pose(0, 0, 0, 0)},
            {"thickness", 2.0},
            {"scale_invariant", true},
            {"points", points},
            {"color", color(c)},
            {"colors", nlohmann::json::array()},
            {"indices", nlohmann::json::array()}}}},
         {"triangles", nlohmann::json::array()},
         {"texts",
          {{{"pose", pose(k.position.x, k.position.y, top + 0.5, 0)},
            {"billboard", true},
            {"font_size", 14.0},
            {"scale_invariant", true},
            {"color", color({1, 1, 1, 1})},
            {"text", text}}}},
         {"models", nlohmann::json::array()}});
  }
  return {{"deletions", {{{"timestamp", stamp(s.stamp)}, {"type", 1}, {"id", ""}}}},  // 1: ALL
          {"entities", entities}};
}

// foxglove.FrameTransform map -> base_link of an ego pose (the sample's frame_id is the parent).
template <class Pose>
nlohmann::json frame_transform_message(const Pose& p) {
  return {{"timestamp", stamp(p.stamp)},
          {"parent_frame_id", p.frame_id},
          {"child_frame_id", "base_link"},
          {"translation", xyz(p.position.x, p.position.y, p.position.z)},
          {"rotation",
           {{"x", p.orientation[0]},
            {"y", p.orientation[1]},
            {"z", p.orientation[2]},
            {"w", p.orientation[3]}}}};
}

// stac.Health: the health sample as named numbers.
template <class Health>
nlohmann::json health_message(const Health& h) {
  nlohmann::json stages = nlohmann::json::object(), drops = nlohmann::json::object();
  for (std::uint32_t i = 0; i < h.stages._length; ++i)
    stages[h.stages._buffer[i].stage] = h.stages._buffer[i].latency_us;
  for (std::uint32_t i = 0; i < h.drops._length; ++i)
    drops[h.drops._buffer[i].cause] = h.drops._buffer[i].count;
  nlohmann::json sensors = nlohmann::json::array();
  for (std::uint32_t i = 0; i < h.sensors._length; ++i) {
    const auto& s = h.sensors._buffer[i];
    sensors.push_back({{"name", s.name}, {"status", s.status}, {"age_s", s.age_s}});
  }
  char hash[17];
  std::snprintf(hash, sizeof hash, "%016llx", static_cast<unsigned long long>(h.model_hash));
  return {{"timestamp", stamp(h.stamp)},
          {"scan_index", h.scan_index},
          {"end_to_end_latency_us", h.end_to_end_latency_us},
          {"deadline_misses", h.deadline_misses},
          {"stages_us", stages},
          {"drops", drops},
          {"sensors", sensors},
          {"model_hash", hash},
          {"model_reloads", h.model_reloads}};
}

}  // namespace stac::view
