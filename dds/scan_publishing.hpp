// A pipeline result as DDS samples: tracked_objects, segments and ego_pose of one scan, converted
// into storage allocated at construction (the IDL bounds) and written by the publishing edge.
// Used by `stac run` (its publisher thread) and `stac process --dds`. Not thread-safe.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "dds/publisher.hpp"
#include "ego/ego_estimator.hpp"
#include "pipeline/scan_pipeline.hpp"
#include "rt/expected.hpp"

namespace stac::dds {

class ScanPublishing {
 public:
  // tentative_tracks false: tracked_objects carries confirmed and coasting tracks only.
  // `classes`: the model's class names (a pipeline without a model: the default ones).
  ScanPublishing(dds::Publisher& publisher, bool tentative_tracks,
                 classification::ClassNames classes);
  // The class names of a pipeline's model, the default ones without a model.
  static classification::ClassNames classes_of(const pipeline::PipelineConfig& config);

  // The point cloud's label of each segment of a result: the class of the track it updated
  // (1..K: the model's class index + 1, K + 1 background; with the default model 1 car ..
  // 4 background), K + 2 when that track is not classified or no track took it. K = `classes`.
  // Fills labels[0, segments).
  static void segment_labels(const pipeline::ScanResult& result, std::size_t classes,
                             std::span<std::uint8_t> labels) noexcept;

  // Checks at start-up that the pipeline's capacities fit the IDL bounds (errors name the key).
  static rt::Status check_capacities(const pipeline::PipelineConfig& config);

  // Publishes tracked_objects, segments and ego_pose; `source`: where the ego pose came from
  // (ego_pose.source: 0 none or lost, 1 INS, 2 CAN dead reckoning). The first failed write is
  // returned (the others are still tried).
  rt::Status publish(const pipeline::ScanResult& result, std::uint64_t scan_index,
                     ego::EgoSource source);
  // Publishes point_cloud when the result has one (PipelineConfig::cloud_stride > 0) and a
  // reader is matched, its returns labelled with their segments' classes: true when written,
  // false when skipped (no cloud built for this scan, or nobody reading). Separate, so that it
  // can go out last.
  rt::Result<bool> publish_cloud(const pipeline::ScanResult& result, std::uint64_t scan_index);
  // Whether a reader of point_cloud was matched at the last publish_cloud() (true before the
  // first): the pipeline builds the cloud only then (ScanPipeline::want_cloud).
  [[nodiscard]] bool cloud_reader() const noexcept { return cloud_reader_; }

 private:
  dds::Publisher& publisher_;
  bool tentative_tracks_ = false;
  classification::ClassNames classes_;
  std::vector<dds::TrackedObjectIn> objects_;
  std::vector<dds::SegmentIn> segments_;
  std::vector<std::uint8_t> segment_labels_;
  std::vector<dds::LabeledPointIn> cloud_;
  bool cloud_reader_ = true;
};

}  // namespace stac::dds
