#include "pipeline/scan_pipeline.hpp"

#include <time.h>

#include <algorithm>
#include <cmath>
#include <optional>

namespace stac::pipeline {
namespace {

std::int64_t now_ns(StageClock c) noexcept;

// Writes the time from its construction to its end into `slot` (ns, the stage's clock).
class StageTimer {
 public:
  StageTimer(StageClock clock, std::int64_t& slot) noexcept
      : clock_(clock), slot_(slot), start_ns_(now_ns(clock)) {}
  ~StageTimer() { slot_ = now_ns(clock_) - start_ns_; }
  StageTimer(const StageTimer&) = delete;
  StageTimer& operator=(const StageTimer&) = delete;

 private:
  StageClock clock_;
  std::int64_t& slot_;
  std::int64_t start_ns_;
};

std::int64_t now_ns(StageClock c) noexcept {
  timespec t{};
  clock_gettime(c == StageClock::kThreadCpu ? CLOCK_THREAD_CPUTIME_ID : CLOCK_MONOTONIC, &t);
  return static_cast<std::int64_t>(t.tv_sec) * 1'000'000'000 + t.tv_nsec;
}

}  // namespace

double yaw_of(const Eigen::Matrix3d& r) noexcept {
  return std::atan2(r(1, 0), r(0, 0));
}

const char* stage_name(Stage s) noexcept {
  switch (s) {
    case kDeskew:
      return "deskew";
    case kSegment:
      return "segment";
    case kTrack:
      return "track";
    case kClassify:
      return "classify";
    case kClassifyDeferred:
      return "classify_deferred";
    case kStageCount:
      break;
  }
  return "?";
}

WorldBox ScanResult::world_box(std::size_t i) const noexcept {
  const segmentation::Segment& s = segments.segments[i];
  const Eigen::Vector3d b = world_T_sensor * Eigen::Vector3d(s.box.cx, s.box.cy, s.box.cz);
  return {b.x(),
          b.y(),
          b.z(),
          s.box.length,
          s.box.width,
          s.box.height,
          s.box.yaw + yaw_of(world_T_sensor.linear())};
}

ScanPipeline::ScanPipeline(const PipelineConfig& config)
    : config_(config),
      deskewer_(config.deskew),
      segmenter_(config.segmenter),
      tracker_(config.tracker),
      classifier_(config.model != nullptr || config.describe
                      ? std::make_unique<classification::TrackClassifier>(
                            [&] {
                              classification::TrackClassifierConfig c = config.classifier;
                              c.max_tracks = config.tracker.max_tracks;
                              c.max_points = config.segmenter.max_points;
                              return c;
                            }(),
                            config.model)
                      : nullptr),
      detections_(config.segmenter.max_segments),
      point_segment_(config.cloud_stride > 0 ? config.segmenter.max_points : 0),
      sensor_T_vehicle_(config.deskew.vehicle_T_sensor.inverse()) {}

ScanResult ScanPipeline::make_result() const {
  return ScanResult(config_.segmenter.max_segments, config_.segmenter.max_points,
                    config_.tracker.max_tracks,
                    config_.cloud_stride > 0 ? config_.cloud_max_points : 0);
}

void ScanPipeline::fill_cloud(const velodyne::Scan& scan, ScanResult& out) noexcept {
  out.cloud.clear();
  out.cloud_dropped = 0;
  out.cloud_origin = out.world_T_sensor.translation();
  out.has_cloud = config_.cloud_stride > 0 && cloud_wanted_.load(std::memory_order_relaxed);
  if (!out.has_cloud) return;
  const std::size_t n = std::min(scan.points.size(), point_segment_.capacity());
  (void)point_segment_.resize(n);
  std::fill_n(point_segment_.begin(), n, kNoSegment);
  const std::size_t segments = std::min<std::size_t>(out.segments.segments.size(), kNoSegment);
  for (std::size_t s = 0; s < segments; ++s) {
    for (const std::uint32_t i : out.segments.indices(out.segments.segments[s])) {
      if (i < n) point_segment_[i] = static_cast<std::uint16_t>(s);
    }
  }
  const Eigen::Matrix3f r = out.world_T_sensor.linear().cast<float>();
  constexpr float kScale = 1.0f / kCloudResolution;
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint16_t seg = point_segment_[i];
    if (seg == kNoSegment && i % config_.cloud_stride != 0) continue;
    const velodyne::Point& p = scan.points[i];
    const Eigen::Vector3f w = r * Eigen::Vector3f(p.x, p.y, p.z) * kScale;  // from the sensor
    CloudPoint* c = w.cwiseAbs().maxCoeff() < 32767.0f ? out.cloud.append() : nullptr;  // NaN: no
    if (c == nullptr) {  // beyond +-327 m, not finite, or the cloud is full
      ++out.cloud_dropped;
      continue;
    }
    c->x = static_cast<std::int16_t>(std::lround(w.x()));
    c->y = static_cast<std::int16_t>(std::lround(w.y()));
    c->z = static_cast<std::int16_t>(std::lround(w.z()));
    c->intensity = static_cast<std::uint8_t>(std::clamp(std::lround(p.intensity), 0L, 255L));
    c->segment = seg;
  }
}

void ScanPipeline::process(velodyne::Scan& scan, const ego::PoseHistory* poses, ScanResult& out,
                           std::int64_t classify_until_ns) noexcept {
  {
    const StageTimer timer(config_.clock, out.stage_ns[kDeskew]);
    place_in_world(scan, poses, out);
  }
  {
    const StageTimer timer(config_.clock, out.stage_ns[kSegment]);
    segmenter_.segment(segmentation::PointView{&scan.points.data()->x, scan.points.size(),
                                               sizeof(velodyne::Point)},
                       out.segments);
  }
  {
    const StageTimer timer(config_.clock, out.stage_ns[kTrack]);
    const Eigen::Vector2f sensor_xy = out.world_T_sensor.translation().head<2>().cast<float>();
    // The world is the INS's frame once a pose came: a scan without one (the INS silent, or its
    // messages refused) cannot be placed in it, so its segments update no track (tracks coast,
    // as in a scan that misses them) rather than land in the vehicle's frame.
    if (out.has_pose || poses == nullptr || poses->pushed() == 0) {
      detect_in_world(out, sensor_xy);
    } else {
      detections_.clear();
    }
    tracker_.update(out.stamp_ns,
                    std::span<const tracking::Detection>(detections_.data(), detections_.size()),
                    out.tracked, &sensor_xy);
  }
  out.classes.clear();
  out.classes_late = out.classes_current = 0;
  out.stage_ns[kClassify] = 0;
  if (classifier_ != nullptr) {
    const StageTimer timer(config_.clock, out.stage_ns[kClassify]);
    classify(scan, out, classify_until_ns);
  }
  fill_cloud(scan, out);  // before the handover: the scan's points are the receiver's again after
  out.stage_ns[kClassifyDeferred] = deferred_classify_ns_;
}

// The scan's clock and, with poses, its deskew and its place in the world (parked: the vehicle's
// frame is the world).
void ScanPipeline::place_in_world(velodyne::Scan& scan, const ego::PoseHistory* poses,
                                  ScanResult& out) noexcept {
  const ego::ScanClock clock =
      ego::scan_clock(scan.header, config_.trailer,
                      poses != nullptr && poses->pushed() > 0
                          ? std::optional<std::int64_t>(poses->newest_stamp_ns())
                          : std::nullopt);
  out.sequence = scan.header.sequence;
  out.receive_stamp_ns = scan.header.stamp_ns;
  out.stamp_ns = scan.header.stamp_ns + clock.scan_to_pose_ns;
  out.clock_source = clock.source;
  out.has_pose = false;
  out.world_T_sensor = config_.deskew.vehicle_T_sensor;  // parked: vehicle = world
  out.world_T_vehicle_start = Eigen::Isometry3d::Identity();
  out.pose = {};
  if (poses != nullptr) {
    const ego::DeskewResult r = deskewer_.apply(scan, *poses, clock.scan_to_pose_ns);
    if (r.ok()) {
      out.has_pose = true;
      out.world_T_sensor = r.world_T_sensor;
      const ego::PoseLookup start = poses->at(out.stamp_ns);
      out.world_T_vehicle_start =
          start.ok() ? ego::to_isometry(start.pose) : r.world_T_sensor * sensor_T_vehicle_;
      out.pose = poses->at(r.reference_ns);
    } else {
      ++without_pose_;
    }
  }
}

// Each segment as a tracker detection in the world frame (end-on boxes completed).
void ScanPipeline::detect_in_world(const ScanResult& out,
                                   const Eigen::Vector2f& sensor_xy) noexcept {
  detections_.clear();
  for (std::size_t i = 0; i < out.segments.segments.size(); ++i) {
    const segmentation::Segment& s = out.segments.segments[i];
    const Eigen::Vector3d c =
        out.world_T_sensor * Eigen::Vector3d(s.centroid[0], s.centroid[1], s.centroid[2]);
    const WorldBox b = out.world_box(i);
    tracking::Detection* d = detections_.append();
    if (d == nullptr) break;  // capacity max_segments: never short
    *d = {c.cast<float>(), Eigen::Vector2d(b.x, b.y).cast<float>(),
          s.box.length,    s.box.width,
          s.box.height,    static_cast<float>(b.yaw),
          s.count,         static_cast<std::uint32_t>(i)};
    (void)tracking::complete_end_on(config_.tracker, sensor_xy, *d);
  }
}

// With split_classification the tracks to publish until classify_until_ns (the rest in
// finish_scan()); else every track.
void ScanPipeline::classify(const velodyne::Scan& scan, ScanResult& out,
                            std::int64_t classify_until_ns) noexcept {
  if (config_.split_classification) {
    classifier_->begin(out.segments, out.tracked);
    const classification::UpdateCount n = classifier_->update(
        &scan.points.data()->x, sizeof(velodyne::Point),
        {.tentative = config_.publish_tentative, .until_ns = classify_until_ns});
    out.classes_late = static_cast<std::uint32_t>(n.late);
    out.classes_current = static_cast<std::uint32_t>(n.classified);
    classifier_->report(out.tracked, out.classes);
  } else {
    classifier_->classify(&scan.points.data()->x, sizeof(velodyne::Point), out.segments,
                          out.tracked, out.classes);
  }
}

void ScanPipeline::finish_scan(const velodyne::Scan& scan) noexcept {
  if (classifier_ == nullptr || !config_.split_classification) return;
  const std::int64_t t0 = now_ns(config_.clock);
  classifier_->finish(&scan.points.data()->x, sizeof(velodyne::Point));
  deferred_classify_ns_ = now_ns(config_.clock) - t0;
}

}  // namespace stac::pipeline
