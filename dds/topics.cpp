#include "dds/topics.hpp"

namespace stac::dds {

const char* topic_suffix(Topic t) noexcept {
  switch (t) {
    case Topic::kTrackedObjects:
      return "tracked_objects";
    case Topic::kSegments:
      return "segments";
    case Topic::kEgoPose:
      return "ego_pose";
    case Topic::kHealth:
      return "health";
    case Topic::kPointCloud:
      return "point_cloud";
  }
  return "?";
}

rt::Result<Topic> topic_from_suffix(std::string_view suffix) {
  std::string valid;
  for (Topic t : kAllTopics) {
    if (suffix == topic_suffix(t)) return t;
    valid += valid.empty() ? "" : ", ";
    valid += topic_suffix(t);
  }
  return rt::make_error("unknown topic '" + std::string(suffix) + "' (topics: " + valid + ")");
}

std::string topic_name(Topic t, const std::string& prefix, bool ros2_names) {
  return (ros2_names ? "rt/" : "") + prefix + "/" + topic_suffix(t);
}

namespace {

QosPtr base_qos(Topic t) {
  QosPtr q(dds_create_qos());
  switch (t) {
    case Topic::kTrackedObjects:
    case Topic::kEgoPose:
      dds_qset_reliability(q.get(), DDS_RELIABILITY_RELIABLE, DDS_MSECS(100));
      dds_qset_history(q.get(), DDS_HISTORY_KEEP_LAST, 1);
      break;
    case Topic::kSegments:
    case Topic::kPointCloud:
      dds_qset_reliability(q.get(), DDS_RELIABILITY_BEST_EFFORT, 0);
      dds_qset_history(q.get(), DDS_HISTORY_KEEP_LAST, 1);
      break;
    case Topic::kHealth:
      dds_qset_reliability(q.get(), DDS_RELIABILITY_RELIABLE, DDS_MSECS(100));
      dds_qset_history(q.get(), DDS_HISTORY_KEEP_LAST, 10);
      break;
  }
  dds_qset_durability(q.get(), DDS_DURABILITY_VOLATILE);
  return q;
}

}  // namespace

QosPtr writer_qos(Topic t) {
  QosPtr q = base_qos(t);
  if (t == Topic::kTrackedObjects || t == Topic::kEgoPose) {
    dds_qset_deadline(q.get(), kTrackDeadline);
    // Cyclone prunes a keep-last writer's unacknowledged sample as soon as `depth` newer ones are
    // written (dds_whc.c), so at depth 1 a sample lost on the wire to a reader that stalled for a
    // moment (its socket buffer full) can never be resent: CI lost 2 of 21 scans that way under
    // load. The writer keeps the last second of scans for retransmission; readers still keep the
    // latest only, and a keep-last writer never blocks.
    dds_qset_history(q.get(), DDS_HISTORY_KEEP_LAST, kWriterRepairDepth);
  }
  return q;
}

QosPtr reader_qos(Topic t) {
  return base_qos(t);
}

rt::Unexpected<rt::Error> dds_error(const std::string& what, dds_return_t rc) {
  return rt::make_error(what + ": " + dds_strretcode(rc));
}

}  // namespace stac::dds
