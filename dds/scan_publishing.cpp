#include "dds/scan_publishing.hpp"

#include <algorithm>
#include <utility>

#include "dds/idl_types.hpp"

namespace stac::dds {

ScanPublishing::ScanPublishing(dds::Publisher& publisher, bool tentative_tracks,
                               classification::ClassNames classes)
    : publisher_(publisher),
      tentative_tracks_(tentative_tracks),
      classes_(std::move(classes)),
      objects_(dds::kMaxObjects),
      segments_(dds::kMaxSegments),
      segment_labels_(dds::kMaxSegments),
      cloud_(dds::kMaxCloudPoints) {}

classification::ClassNames ScanPublishing::classes_of(const pipeline::PipelineConfig& config) {
  return config.model ? config.model->classes : classification::default_class_names();
}

void ScanPublishing::segment_labels(const pipeline::ScanResult& r, std::size_t classes,
                                    std::span<std::uint8_t> labels) noexcept {
  const std::size_t n = std::min(r.segments.segments.size(), labels.size());
  std::fill_n(labels.begin(), n, static_cast<std::uint8_t>(classes + 2));
  for (std::size_t i = 0; i < r.tracked.tracks.size() && i < r.classes.size(); ++i) {
    const tracking::Track& t = r.tracked.tracks[i];
    if (t.segment < 0 || static_cast<std::size_t>(t.segment) >= n || !r.classes[i].classified)
      continue;
    // Class index k -> label k + 1, background -> K + 1 (the track's prediction).
    const classification::ClassIndex c = r.classes[i].label;
    labels[static_cast<std::size_t>(t.segment)] =
        static_cast<std::uint8_t>((c == classification::kBackground ? classes : c) + 1);
  }
}

rt::Status ScanPublishing::check_capacities(const pipeline::PipelineConfig& config) {
  if (config.tracker.max_tracks > dds::kMaxObjects) {
    return rt::make_error("'tracking.max_tracks' " + std::to_string(config.tracker.max_tracks) +
                          " exceeds the tracked_objects bound of " +
                          std::to_string(dds::kMaxObjects) + " (idl/stac.idl)");
  }
  if (config.segmenter.max_segments > dds::kMaxSegments) {
    return rt::make_error(
        "'segmentation.max_segments' " + std::to_string(config.segmenter.max_segments) +
        " exceeds the segments bound of " + std::to_string(dds::kMaxSegments) + " (idl/stac.idl)");
  }
  return {};
}

rt::Status ScanPublishing::publish(const pipeline::ScanResult& r, std::uint64_t scan_index,
                                   ego::EgoSource source) {
  const dds::ScanStamp stamp{r.stamp_ns, scan_index};
  std::size_t n_tracks = 0;
  for (std::size_t i = 0; i < r.tracked.tracks.size() && n_tracks < objects_.size(); ++i) {
    if (!tentative_tracks_ && r.tracked.tracks[i].state == tracking::TrackState::kTentative)
      continue;
    dds::TrackedObjectIn& o = objects_[n_tracks++];
    o = dds::to_tracked_object(r.tracked.tracks[i]);
    if (i < r.classes.size() && r.classes[i].classified) {
      // Background's log odds: minus the largest foreground one, so it is positive exactly
      // when every foreground class is negative (the thesis's prediction rule).
      const classification::LogOdds& l = r.classes[i].log_odds;
      const std::size_t classes = classes_.size();
      o.classified = true;
      o.class_names = classes_;
      o.class_log_odds = {};
      std::copy_n(l.begin(), classes, o.class_log_odds.begin());
      o.class_log_odds[classes] = -*std::max_element(l.begin(), l.begin() + classes);
      o.class_age = r.classes[i].age;
    }
  }
  rt::Status status = publisher_.publish_tracked_objects(stamp, {objects_.data(), n_tracks});

  const std::size_t n_segments =
      std::min<std::size_t>(r.segments.segments.size(), segments_.size());
  for (std::size_t i = 0; i < n_segments; ++i) {
    const pipeline::WorldBox b = r.world_box(i);
    segments_[i] = {static_cast<std::uint32_t>(i),
                    {b.x, b.y, b.z},
                    {b.length, b.width, b.height},
                    static_cast<float>(b.yaw),
                    r.segments.segments[i].count};
  }
  if (auto s = publisher_.publish_segments(stamp, {segments_.data(), n_segments}); !s && status)
    status = s;

  dds::EgoPoseIn pose;
  pose.stamp_ns = r.stamp_ns;
  if (r.pose.ok()) {
    const ego::PoseSample& p = r.pose.pose;
    pose.stamp_ns = p.stamp_ns;
    pose.position = {p.position_m.x(), p.position_m.y(), p.position_m.z()};
    pose.orientation = {p.attitude.x(), p.attitude.y(), p.attitude.z(), p.attitude.w()};
    pose.velocity = {p.velocity_mps.x(), p.velocity_mps.y(), p.velocity_mps.z()};
    pose.yaw_rate = static_cast<float>(p.angular_rate_rps.z());
    pose.source = source == ego::EgoSource::kIns             ? 1
                  : source == ego::EgoSource::kDeadReckoning ? 2
                                                             : 0;
  } else {
    const Eigen::Vector3d t = r.world_T_vehicle_start.translation();
    const Eigen::Quaterniond q(r.world_T_vehicle_start.linear());
    pose.position = {t.x(), t.y(), t.z()};
    pose.orientation = {q.x(), q.y(), q.z(), q.w()};
    pose.source = 0;
  }
  if (auto s = publisher_.publish_ego_pose(pose); !s && status) status = s;
  return status;
}

rt::Result<bool> ScanPublishing::publish_cloud(const pipeline::ScanResult& r,
                                               std::uint64_t scan_index) {
  // Asked once a scan, whether or not this scan has a cloud: the pipeline builds the next ones
  // from what is found here (cloud_reader()).
  dds_publication_matched_status_t matched{};
  cloud_reader_ = dds_get_publication_matched_status(publisher_.writer(dds::Topic::kPointCloud),
                                                     &matched) != 0 ||
                  matched.current_count > 0;  // unknown: as if there were one
  // Not built for this scan (dds.point_cloud_stride 0, or nobody read the last one): nothing
  // to send, not an empty cloud.
  if (!r.has_cloud) return false;
  // Only for a reader: Cyclone serializes a sample even when nobody reads it (about 1 ms for a
  // 40k-point cloud), and this topic's readers are viewers, which come and go.
  if (!cloud_reader_) return false;
  const dds::ScanStamp stamp{r.stamp_ns, scan_index};
  const std::size_t n_segments =
      std::min<std::size_t>(r.segments.segments.size(), segment_labels_.size());
  segment_labels(r, classes_.size(), segment_labels_);
  const std::size_t n = std::min(r.cloud.size(), cloud_.size());
  for (std::size_t i = 0; i < n; ++i) {
    const pipeline::CloudPoint& c = r.cloud[i];
    const bool in_segment = c.segment < n_segments;
    cloud_[i] = {c.x,
                 c.y,
                 c.z,
                 c.intensity,
                 in_segment ? segment_labels_[c.segment] : std::uint8_t{0},
                 in_segment ? static_cast<std::uint16_t>(c.segment) : dds::kNoSegment};
  }
  const dds::PointCloudIn cloud{stamp,
                                {r.cloud_origin.x(), r.cloud_origin.y(), r.cloud_origin.z()},
                                pipeline::kCloudResolution,
                                {cloud_.data(), n}};
  if (auto written = publisher_.publish_point_cloud(cloud); !written)
    return rt::Unexpected<rt::Error>{std::move(written).error()};
  return true;
}

}  // namespace stac::dds
