// One scan through perception, in fixed memory: deskew (with the pose history, when there is
// one) -> segment -> detections in the world frame -> track -> classify (with a model). The
// constructor allocates everything; process() allocates nothing and throws nothing. The caller owns
// the ScanResult (from make_result()), so results can live in the slots of a thread handover.
//
//   ScanPipeline pipeline(config);  ScanResult r = pipeline.make_result();
//   pipeline.process(scan, poses, r);   // poses: nullptr for a parked sensor (world = vehicle)
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>

#include "drivers/velodyne/model.hpp"
#include "drivers/velodyne/scan.hpp"
#include "ego/deskew.hpp"
#include "ego/pose_history.hpp"
#include "ego/time_sync.hpp"
#include "perception/classification/track_classifier.hpp"
#include "perception/segmentation/segmenter.hpp"
#include "perception/tracking/tracker.hpp"

namespace stac::pipeline {

// Which clock the per-stage times are read on.
enum class StageClock : std::uint8_t {
  kThreadCpu,  // CPU time of the calling thread: a stage's cost on one core (offline figures)
  kMonotonic,  // CLOCK_MONOTONIC: latency as a live deadline sees it
};

struct PipelineConfig {
  ego::DeskewConfig deskew;  // its vehicle_T_sensor is also the parked sensor's pose
  segmentation::SegmenterConfig segmenter;
  tracking::TrackerConfig tracker;
  classification::TrackClassifierConfig classifier;  // its max_tracks is the tracker's
  std::shared_ptr<const classification::TrackClassifierModel> model;  // null: tracks unclassified
  bool describe = false;  // run the classify stage without a model too (an observer's descriptors)
  // true: process() classifies only the tracks it will publish (confirmed ones; tentative ones
  // too with publish_tentative), and only until its classify_until_ns; finish_scan() classifies
  // the others and grows the tracks' accumulated clouds after the result is handed on (stac run:
  // the costly part waits until the scan is published; docs/run.md). false: process() does all.
  bool split_classification = false;
  bool publish_tentative = false;
  velodyne::TrailerKind trailer = velodyne::TrailerKind::kGpsStatus;  // the model's (scan clock)
  // The compact cloud for viewers (ScanResult::cloud): every return in a kept segment and every
  // cloud_stride-th other one, at most cloud_max_points; cloud_stride 0: none.
  std::uint32_t cloud_stride = 0;
  std::size_t cloud_max_points = 131072;
  StageClock clock = StageClock::kThreadCpu;
};

// kClassify: process()'s part of the classification; kClassifyDeferred: the previous scan's
// finish_scan() (0 unless split_classification).
enum Stage : std::uint8_t { kDeskew, kSegment, kTrack, kClassify, kClassifyDeferred, kStageCount };
const char* stage_name(Stage s) noexcept;  // "deskew", ..., "classify", "classify_deferred"

// The heading (rad, about z) of a rotation: atan2(r10, r00).
double yaw_of(const Eigen::Matrix3d& r) noexcept;

// One return of ScanResult::cloud: world-frame offset from the cloud's origin (the sensor) in
// units of kCloudResolution, intensity 0..255, the index of its segment (kNoSegment: none).
inline constexpr float kCloudResolution = 0.01f;  // m: +-327 m in int16
inline constexpr std::uint16_t kNoSegment = 0xFFFF;
struct CloudPoint {
  std::int16_t x = 0, y = 0, z = 0;
  std::uint8_t intensity = 0;
  std::uint16_t segment = kNoSegment;
};

// A box in the world frame (m, rad).
struct WorldBox {
  double x = 0, y = 0, z = 0, length = 0, width = 0, height = 0, yaw = 0;
};

struct ScanResult {
  ScanResult(std::size_t max_segments, std::size_t max_points, std::size_t max_tracks,
             std::size_t max_cloud = 0)
      : segments(max_segments, max_points),
        tracked(max_tracks),
        classes(max_tracks),
        cloud(max_cloud) {}

  std::uint64_t sequence = 0;         // the scan's sequence number (ScanHeader)
  std::int64_t receive_stamp_ns = 0;  // the scan's stamp on the receive clock (ScanHeader)
  std::int64_t stamp_ns = 0;          // the same instant on the pose clock (UTC): results' time
  ego::ScanClockSource clock_source = ego::ScanClockSource::kReceive;
  bool has_pose = false;  // deskewed and placed in the world by the pose history
  Eigen::Isometry3d world_T_sensor = Eigen::Isometry3d::Identity();         // at the last firing
  Eigen::Isometry3d world_T_vehicle_start = Eigen::Isometry3d::Identity();  // at the scan's stamp
  ego::PoseLookup pose;             // the vehicle pose at stamp_ns (status kEmpty: none)
  segmentation::Segments segments;  // sensor frame (see world_box())
  tracking::TrackerOutput tracked;  // world frame
  rt::FixedVector<classification::TrackClass> classes;  // classes[i]: tracked.tracks[i]'s class
                                                        // (empty when the stage does not run)
  std::int64_t stage_ns[kStageCount] = {};              // on PipelineConfig::clock
  // split_classification: tracks to publish whose segment process() left to finish_scan() when
  // its time was up (their class is the one the scans before left).
  std::uint32_t classes_late = 0;
  std::uint32_t classes_current = 0;  // tracks to publish that process() classified
  rt::FixedVector<CloudPoint> cloud;  // PipelineConfig::cloud_stride > 0; origin below
  bool has_cloud = false;  // the cloud was built for this scan (cloud_stride > 0 and wanted)
  Eigen::Vector3d cloud_origin = Eigen::Vector3d::Zero();  // world (m): world_T_sensor's
  std::uint64_t cloud_dropped = 0;  // returns for the cloud beyond its capacity or +-327 m

  // Segment i's box in the world frame.
  [[nodiscard]] WorldBox world_box(std::size_t i) const noexcept;
};

class ScanPipeline {
 public:
  explicit ScanPipeline(const PipelineConfig& config);

  [[nodiscard]] ScanResult make_result() const;
  // One scan (deskewed in place). `poses` may be nullptr: no deskew, the sensor parked at
  // vehicle_T_sensor in the world. With split_classification, no track is classified from
  // `classify_until_ns` on (CLOCK_REALTIME; the scan's last firing + a budget).
  void process(velodyne::Scan& scan, const ego::PoseHistory* poses, ScanResult& out,
               std::int64_t classify_until_ns = classification::UpdateLimit::kNoLimit) noexcept;

  // With split_classification: the classification process() left of the last scan, which must
  // be `scan`, its points unchanged (its Segments may have changed); its time is the next
  // result's stage_ns[kClassifyDeferred]. No-op otherwise. No allocation, exception or I/O.
  void finish_scan(const velodyne::Scan& scan) noexcept;

  [[nodiscard]] const tracking::Tracker& tracker() const noexcept { return tracker_; }
  // Null when the classify stage does not run (no model, describe off).
  [[nodiscard]] classification::TrackClassifier* classifier() noexcept { return classifier_.get(); }
  [[nodiscard]] std::uint64_t scans_without_pose() const noexcept { return without_pose_; }
  // Whether process() builds the cloud (with cloud_stride > 0; true at start): the publisher
  // says whether a viewer reads it, so that nobody pays for it otherwise. Any thread.
  void want_cloud(bool wanted) noexcept { cloud_wanted_.store(wanted, std::memory_order_relaxed); }

 private:
  PipelineConfig config_;
  ego::Deskewer deskewer_;
  segmentation::Segmenter segmenter_;
  tracking::Tracker tracker_;
  std::unique_ptr<classification::TrackClassifier> classifier_;
  rt::FixedVector<tracking::Detection> detections_;
  rt::FixedVector<std::uint16_t> point_segment_;  // per point: its segment (cloud_stride > 0)
  // The stages of process(), in order (segmentation and tracking are calls of their own).
  void place_in_world(velodyne::Scan& scan, const ego::PoseHistory* poses,
                      ScanResult& out) noexcept;
  void detect_in_world(const ScanResult& out, const Eigen::Vector2f& sensor_xy) noexcept;
  void classify(const velodyne::Scan& scan, ScanResult& out,
                std::int64_t classify_until_ns) noexcept;
  void fill_cloud(const velodyne::Scan& scan, ScanResult& out) noexcept;
  Eigen::Isometry3d sensor_T_vehicle_;
  std::uint64_t without_pose_ = 0;
  std::int64_t deferred_classify_ns_ = 0;  // the last finish_scan()'s time
  std::atomic<bool> cloud_wanted_{true};
};

}  // namespace stac::pipeline
