#include "tools/track_describer.hpp"

#include <algorithm>

namespace stac::tools {

void TrackDescriber::describe(const velodyne::Scan& scan, const pipeline::ScanResult& result,
                              const tracking::Track& track) {
  auto it = clouds_.find(track.id);
  if (it == clouds_.end()) {
    it = clouds_
             .emplace(track.id, std::make_unique<classification::AccumulatedCloud>(
                                    kAccumulatedCapacity, track.id + 1))
             .first;
  }
  const segmentation::Segment& seg =
      result.segments.segments[static_cast<std::size_t>(track.segment)];
  const descriptors::SegmentView view{&scan.points.data()->x, sizeof(velodyne::Point),
                                      result.segments.indices(seg), 0};
  describer_.compute(view, segment_);
  it->second->add_segment(view);
  describer_.compute(it->second->view(), accumulated_);
  classification::holistic_descriptor(track, &accumulated_, holistic_);
}

const std::vector<std::uint64_t>& TrackDescriber::end_scan(const pipeline::ScanResult& result) {
  ended_.clear();
  for (auto it = clouds_.begin(); it != clouds_.end();) {
    const auto& tracks = result.tracked.tracks;
    const bool live = std::any_of(tracks.begin(), tracks.end(),
                                  [&](const tracking::Track& t) { return t.id == it->first; });
    if (live) {
      ++it;
    } else {
      ended_.push_back(it->first);
      it = clouds_.erase(it);
    }
  }
  return ended_;
}

std::vector<std::uint64_t> TrackDescriber::end_all() {
  std::vector<std::uint64_t> ids;
  for (const auto& [id, cloud] : clouds_) ids.push_back(id);
  clouds_.clear();
  return ids;
}

}  // namespace stac::tools
