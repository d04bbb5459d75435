// Topic names and QoS of STAC's DDS topics, shared by the publisher, `stac echo` and tests.
#pragma once

#include <dds/dds.h>

#include <cstdint>
#include <memory>
#include <string>
#include <string_view>

#include "rt/expected.hpp"

namespace stac::dds {

enum class Topic { kTrackedObjects, kSegments, kEgoPose, kHealth, kPointCloud };
inline constexpr Topic kAllTopics[] = {Topic::kTrackedObjects, Topic::kSegments, Topic::kEgoPose,
                                       Topic::kHealth, Topic::kPointCloud};

// "tracked_objects", "segments", "ego_pose", "health", "point_cloud"
const char* topic_suffix(Topic t) noexcept;
// The suffix back to the topic; an error listing the valid ones.
rt::Result<Topic> topic_from_suffix(std::string_view suffix);

// "<prefix>/<suffix>", and in ROS 2 naming mode "rt/<prefix>/<suffix>" (ROS topic /<prefix>/...).
std::string topic_name(Topic t, const std::string& prefix, bool ros2_names);

// The QoS of a topic (docs/dds.md): tracked objects and ego pose reliable with a 100 ms deadline,
// their writers keep-last kWriterRepairDepth (what a stalled reader may still be resent), their
// readers keep-last 1; segments and the point cloud best effort keep-last 1; health reliable
// keep-last 10. Readers use the writers' QoS without the deadline.
struct QosDeleter {
  void operator()(dds_qos_t* q) const noexcept { dds_delete_qos(q); }
};
using QosPtr = std::unique_ptr<dds_qos_t, QosDeleter>;
QosPtr writer_qos(Topic t);
QosPtr reader_qos(Topic t);
inline constexpr dds_duration_t kTrackDeadline = DDS_MSECS(100);
inline constexpr int32_t kWriterRepairDepth = 10;  // one second of scans at 10 Hz

// "what: <Cyclone's retcode text>" for a negative Cyclone return value.
rt::Unexpected<rt::Error> dds_error(const std::string& what, dds_return_t rc);

}  // namespace stac::dds
