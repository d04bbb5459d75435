#include "runtime/health.hpp"

#include <algorithm>
#include <climits>

#include "rt/clock.hpp"

namespace stac::runtime {
namespace {

// The IDL's sensor status: 0 ok, 1 stalled, 2 lost, 3 not configured.
std::uint8_t sensor_status(const rt::InputStatus& s) noexcept {
  switch (s.state) {
    case rt::InputState::kOk:
      return 0;
    case rt::InputState::kStalled:
      return 1;
    case rt::InputState::kLost:
      return 2;
    case rt::InputState::kNotConfigured:
      return 3;
  }
  return 2;
}

}  // namespace

std::uint32_t to_us(std::int64_t ns) noexcept {
  return static_cast<std::uint32_t>(std::clamp<std::int64_t>(ns / 1000, 0, UINT32_MAX));
}

void HealthAssembly::set_frame(const Frame& f) noexcept {
  const tracking::TrackerCounters& tc = f.result.tracked.counters;
  frame_ = {f.segment_overflow, f.without_pose, tc.pool_overflow, tc.dropped_detections,
            f.classes_late};
}

dds::HealthIn HealthAssembly::sample(std::int64_t stamp_ns, std::uint64_t index,
                                     std::span<const dds::StageLatencyIn> stages,
                                     std::int64_t end_to_end_ns) noexcept {
  Component::Live& l = live_;
  const std::int64_t now = rt::monotonic_ns();
  l.watchdog.update(now);
  const can::CanInputCounters cc = l.can_cells.load();
  const auto n = [&](Count c) { return l.counts.get(c); };
  drops_ = {dds::DropCountIn{"velodyne.kernel", n(Count::kKernelDrops)},
            {"velodyne.wrong_size", n(Count::kWrongSize)},
            {"velodyne.invalid_block", n(Count::kInvalidBlock)},
            {"velodyne.duplicates", n(Count::kDuplicates)},
            {"velodyne.late_firings", n(Count::kLateFirings)},
            {"velodyne.other_model", n(Count::kOtherModel)},
            {"velodyne.scan_slots_full", l.stream->scans_dropped()},
            // Scans not processed have no frame: these two are live, so that a health sample
            // while none is published (lost bursts, a dropout) shows them (issue 31).
            {"velodyne.incomplete_scan", n(Count::kIncomplete)},
            {"velodyne.packets_lost", n(Count::kPacketsLost)},
            {"results.slots_full", l.results->dropped()},
            {"segmentation.overflow", frame_.segment_overflow},
            {"tracking.pool_full", frame_.pool_overflow},
            {"tracking.detections", frame_.dropped_detections},
            {"dds.errors", n(Count::kPublishErrors)},
            {"pose.rejected", l.history->rejected()},
            {"ins.bad_checksum", n(Count::kInsBadChecksum)},
            {"ins.bad_framing", n(Count::kInsBadFraming)},
            {"ins.malformed", n(Count::kInsMalformed)},
            {"ins.garbage_bytes", n(Count::kInsGarbageBytes)},
            {"ins.connect_failures", n(Count::kInsConnectFailures)},
            {"ins.disconnects", n(Count::kInsDisconnects)},
            {"ego.scans_without_pose", frame_.without_pose},
            {"classification.late", frame_.classes_late},
            {"can.not_mapped", cc.not_mapped},
            {"can.overflow", cc.kernel_drops + cc.overflows +
                                 l.can_cells.ring_full.load(std::memory_order_relaxed)},
            {"can.fd", cc.can_fd},
            {"can.malformed", cc.malformed},
            {"can.other_channel", cc.other_channel},
            {"can.lost", cc.lost},
            {"model.reload_refused", n(Count::kModelRefused)}};
  for (std::size_t i = 0; i < sensors_.size(); ++i) {
    const rt::InputStatus st = l.watchdog.status(i, now);
    sensors_[i] = {kInputNames[i], sensor_status(st),
                   static_cast<float>(static_cast<double>(st.age_ns) * 1e-9)};
  }
  return dds::HealthIn{.scan = {stamp_ns, index},
                       .stages = stages,
                       .end_to_end_latency_us = to_us(end_to_end_ns),
                       .deadline_misses = l.monitor->misses(),
                       .drops = drops_,
                       .sensors = sensors_,
                       .model_hash = l.model_handover.hash.load(std::memory_order_relaxed),
                       .model_reloads = l.model_handover.reloads.load(std::memory_order_relaxed)};
}

}  // namespace stac::runtime
