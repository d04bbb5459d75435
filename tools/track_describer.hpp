// Per-track descriptors as `stac dataset` records them and `stac process --model` classifies
// them: each segment a track is updated with is described, added to the track's accumulated
// cloud, and the track's holistic descriptor after it computed (docs/classification.md).
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <span>
#include <vector>

#include "drivers/velodyne/scan.hpp"
#include "perception/classification/accumulated_cloud.hpp"
#include "perception/classification/holistic.hpp"
#include "perception/descriptors/descriptors.hpp"
#include "pipeline/scan_pipeline.hpp"

namespace stac::tools {

inline constexpr std::size_t kAccumulatedCapacity = 4096;  // points per track's cloud

class TrackDescriber {
 public:
  // The descriptors of `track`'s segment this scan (track.segment >= 0) and its holistic
  // descriptor after it; valid until the next call.
  void describe(const velodyne::Scan& scan, const pipeline::ScanResult& result,
                const tracking::Track& track);
  [[nodiscard]] std::span<const float> segment() const noexcept { return segment_.values; }
  [[nodiscard]] std::span<const float> holistic() const noexcept { return holistic_; }
  // Drops the clouds of tracks the tracker no longer reports; returns their ids.
  const std::vector<std::uint64_t>& end_scan(const pipeline::ScanResult& result);
  // Ids of every track still held (at the end of a capture); drops them all.
  std::vector<std::uint64_t> end_all();

 private:
  std::map<std::uint64_t, std::unique_ptr<classification::AccumulatedCloud>> clouds_;
  std::vector<std::uint64_t> ended_;
  descriptors::DescriptorPipeline describer_{descriptors::DescriptorConfig{}};
  descriptors::Descriptors segment_, accumulated_;
  classification::HolisticDescriptor holistic_{};
};

}  // namespace stac::tools
