// The Foxglove messages of view: base64, the point cloud's bytes, a track's entity, paths.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "dds/idl_types.hpp"
#include "view/foxglove_messages.hpp"

namespace stac::view {
namespace {

using Types = dds::IdlTypes<false>;

std::string decode64(const std::string& s) {
  const std::string alphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  unsigned bits = 0, n = 0;
  for (char c : s) {
    if (c == '=') break;
    n = n << 6 | static_cast<unsigned>(alphabet.find(c));
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      out.push_back(static_cast<char>((n >> bits) & 0xFF));
    }
  }
  return out;
}

TEST(Base64, MatchesTheRfc4648Vectors) {
  EXPECT_EQ(base64(""), "");
  EXPECT_EQ(base64("f"), "Zg==");
  EXPECT_EQ(base64("fo"), "Zm8=");
  EXPECT_EQ(base64("foo"), "Zm9v");
  EXPECT_EQ(base64("foob"), "Zm9vYg==");
  EXPECT_EQ(base64("fooba"), "Zm9vYmE=");
  EXPECT_EQ(base64("foobar"), "Zm9vYmFy");
  std::string bytes;
  for (int i = 0; i < 256; ++i) bytes.push_back(static_cast<char>(i));
  EXPECT_EQ(decode64(base64(bytes)), bytes);
}

TEST(PointCloudMessage, EachPointIsItsPositionIntensityLabelSegmentAndSegmentColour) {
  std::vector<Types::LabeledPoint> points = {{100, -200, 30, 7, 1, 4},
                                             {-5, 0, 0, 255, 0, dds::kNoSegment}};
  Types::LabeledPointCloud cloud{};
  cloud.stamp = {12, 500};
  std::strcpy(cloud.frame_id, "map");
  cloud.scan_index = 42;
  cloud.origin = {1.0, 2.0, 3.0};
  cloud.resolution = 0.01f;
  cloud.points._length = static_cast<std::uint32_t>(points.size());
  cloud.points._buffer = points.data();
  const nlohmann::json j = point_cloud_message(cloud);
  EXPECT_EQ(j["frame_id"], "map");
  EXPECT_EQ(j["timestamp"]["sec"], 12);
  EXPECT_EQ(j["timestamp"]["nsec"], 500);
  EXPECT_EQ(j["scan_index"], 42);
  EXPECT_DOUBLE_EQ(j["pose"]["position"]["y"].get<double>(), 2.0);
  EXPECT_EQ(j["point_stride"], kPointStride);
  ASSERT_EQ(j["fields"].size(), 10u);
  EXPECT_EQ(j["fields"][9]["name"], "segment");
  EXPECT_EQ(j["fields"][9]["offset"], 18);
  EXPECT_EQ(j["fields"][9]["type"], 3);  // UINT16
  EXPECT_EQ(j["fields"][3]["name"], "intensity");
  EXPECT_EQ(j["fields"][3]["offset"], 12);
  EXPECT_EQ(j["fields"][3]["type"], 1);  // UINT8
  const std::string data = decode64(j["data"].get<std::string>());
  ASSERT_EQ(data.size(), 2 * kPointStride);
  float xyz[3];
  std::memcpy(xyz, data.data(), sizeof xyz);
  EXPECT_FLOAT_EQ(xyz[0], 1.0f);
  EXPECT_FLOAT_EQ(xyz[1], -2.0f);
  EXPECT_FLOAT_EQ(xyz[2], 0.3f);
  EXPECT_EQ(static_cast<unsigned char>(data[12]), 7);  // intensity
  EXPECT_EQ(static_cast<unsigned char>(data[13]), 1);  // label: car
  std::uint16_t segment = 0;
  std::memcpy(&segment, data.data() + 18, sizeof segment);
  EXPECT_EQ(segment, 4);
  const Rgba four = segment_color(4);
  EXPECT_EQ(static_cast<unsigned char>(data[14]), std::lround(four.r * 255));
  EXPECT_EQ(static_cast<unsigned char>(data[16]), std::lround(four.b * 255));
  EXPECT_EQ(static_cast<unsigned char>(data[kPointStride + 12]), 255);
  EXPECT_EQ(static_cast<unsigned char>(data[kPointStride + 13]), 0);
  std::memcpy(&segment, data.data() + kPointStride + 18, sizeof segment);
  EXPECT_EQ(segment, dds::kNoSegment);
  EXPECT_EQ(static_cast<unsigned char>(data[kPointStride + 14]), 89);  // dark grey: no segment
}

TEST(SegmentColor, NeighbouringSegmentsDiffer) {
  for (std::uint16_t s = 0; s < 2047; ++s) {
    const Rgba a = segment_color(s), b = segment_color(static_cast<std::uint16_t>(s + 1));
    EXPECT_FALSE(a.r == b.r && a.g == b.g && a.b == b.b) << s;
  }
}

Types::TrackedObject object(std::uint64_t id, double x, double vx,
                            Types::ObjectClassification* cls) {
  Types::TrackedObject o{};
  o.object_id = id;
  o.kinematics.position = {x, 5.0, 0.8};
  o.kinematics.velocity = {vx, 0.0, 0.0};
  o.shape.dimensions = {4.5, 1.8, 1.6};
  o.shape.yaw = 0.5f;
  o.classification._length = 1;
  o.classification._buffer = cls;
  o.state = 1;
  return o;
}

TEST(SceneUpdateMessage, ABoxTextArrowAndPathPerTrackAfterDeletingTheLastScans) {
  Types::ObjectClassification car{1, 0.9f, "car"};
  Types::ObjectClassification unsure{1, 0.4f, "car"};
  std::vector<Types::TrackedObject> objects = {object(7, 10.0, 3.0, &car),
                                               object(9, 20.0, 0.0, &unsure)};
  Types::TrackedObjects s{};
  s.stamp = {3, 0};
  std::strcpy(s.frame_id, "map");
  s.scan_index = 5;
  s.objects._length = 2;
  s.objects._buffer = objects.data();
  TrackPaths paths;
  paths.update(s);
  objects[0].kinematics.position.x = 10.3;
  paths.update(s);
  const nlohmann::json j = scene_update_message(s, paths);
  ASSERT_EQ(j["deletions"].size(), 1u);
  EXPECT_EQ(j["deletions"][0]["type"], 1);  // ALL
  ASSERT_EQ(j["entities"].size(), 2u);
  const nlohmann::json& e = j["entities"][0];
  EXPECT_EQ(e["id"], "track/7");
  EXPECT_EQ(e["texts"][0]["text"], "#7 car 3.0 m/s");
  EXPECT_EQ(e["arrows"].size(), 1u);              // it moves
  EXPECT_EQ(e["lines"][0]["points"].size(), 2u);  // two scans of path
  EXPECT_DOUBLE_EQ(e["cubes"][0]["size"]["x"].get<double>(), 4.5);
  EXPECT_DOUBLE_EQ(e["cubes"][0]["color"]["b"].get<double>(), 1.0);  // cars are blue
  const nlohmann::json& f = j["entities"][1];
  EXPECT_EQ(f["texts"][0]["text"], "#9 unknown 0.0 m/s");  // probability 0.4: not shown as car
  EXPECT_EQ(f["arrows"].size(), 0u);                       // standing
}

TEST(TrackPaths, KeepTheLastHundredCentresAndForgetTracksThatAreGone) {
  Types::ObjectClassification car{1, 0.9f, "car"};
  std::vector<Types::TrackedObject> objects = {object(1, 0.0, 1.0, &car)};
  Types::TrackedObjects s{};
  s.objects._length = 1;
  s.objects._buffer = objects.data();
  TrackPaths paths;
  for (int i = 0; i < 150; ++i) {
    objects[0].kinematics.position.x = i;
    paths.update(s);
  }
  ASSERT_EQ(paths.path(1).size(), TrackPaths::kMaxPathPoints);
  EXPECT_DOUBLE_EQ(paths.path(1).front().x, 50.0);
  EXPECT_DOUBLE_EQ(paths.path(1).back().x, 149.0);
  s.objects._length = 0;
  paths.update(s);
  EXPECT_THROW((void)paths.path(1), std::out_of_range);
}

}  // namespace
}  // namespace stac::view
