// The publisher thread: each result on DDS (tracked_objects, segments, ego_pose, health, then the
// point cloud), its latencies into the deadline monitor. Sleeps until perception has a result;
// while none comes, a health sample every 100 ms, so that subscribers see a silent or dead
// sensor within a scan period. Ends when perception has ended and every result is published.
#include <algorithm>
#include <array>
#include <cstdio>

#include "rt/clock.hpp"
#include "runtime/health.hpp"

namespace stac::runtime {
namespace {

// While no scan is published, a health sample (without stages) every 100 ms: the scan period at
// 600 rpm, so a lidar that goes silent shows as stale on health within a scan of the watchdog
// noticing (issue 31), whatever the sensor did before.
constexpr std::int64_t kIdleHealthNs = 100'000'000;

}  // namespace

void publisher_loop(Component::Live& live) noexcept {
  rt::SlotExchange<Frame>& results = *live.results;
  dds::ScanPublishing& scan_publishing = *live.scan_publishing;
  dds::Publisher& publisher = *live.publisher;
  HealthAssembly health(live);
  std::array<std::int64_t, kHealthStages> stage_ns{};
  std::array<dds::StageLatencyIn, kHealthStages> stages{};
  bool reported = false;
  std::int64_t last_health_ns = rt::monotonic_ns();
  for (;;) {
    const std::uint32_t seen = live.results_ready.generation();
    Frame* f = results.take();
    if (f == nullptr) {
      if (!live.perception_done.load(std::memory_order_acquire)) {
        const std::int64_t since = rt::monotonic_ns() - last_health_ns;
        if (since >= kIdleHealthNs) {
          const std::uint64_t published = live.counts.get(Count::kPublished);
          const dds::HealthIn h =
              health.sample(rt::realtime_ns(), published == 0 ? 0 : published - 1, {}, 0);
          if (auto r = publisher.publish_health(h); !r) live.counts.add(Count::kPublishErrors);
          last_health_ns = rt::monotonic_ns();
          continue;
        }
        live.results_ready.wait(seen, std::max<std::int64_t>(kIdleHealthNs - since, 1));
        continue;
      }
      if ((f = results.take()) == nullptr) break;
    }
    const std::int64_t t0 = rt::realtime_ns();
    const std::uint64_t index = live.counts.get(Count::kPublished);
    auto status =
        scan_publishing.publish(f->result, index, live.ego_source.load(std::memory_order_relaxed));
    const std::int64_t t1 = rt::realtime_ns();
    const std::int64_t end_to_end = t1 - f->last_firing_ns;
    stage_ns = {f->started_ns - f->last_firing_ns,
                f->result.stage_ns[pipeline::kDeskew],
                f->result.stage_ns[pipeline::kSegment],
                f->result.stage_ns[pipeline::kTrack],
                f->result.stage_ns[pipeline::kClassify],
                f->result.stage_ns[pipeline::kClassifyDeferred],
                t0 - f->finished_ns,
                t1 - t0};
    (void)live.monitor->record(stage_ns, end_to_end);
    for (std::size_t i = 0; i < kHealthStages; ++i)
      stages[i] = {kStageNames[i], to_us(stage_ns[i])};
    health.set_frame(*f);
    const dds::HealthIn h = health.sample(f->result.stamp_ns, index, stages, end_to_end);
    if (auto r = publisher.publish_health(h); !r && status) status = r;
    last_health_ns = rt::monotonic_ns();
    // The viewers' cloud last, outside the scan's end-to-end latency (it is the largest sample).
    if (auto c = scan_publishing.publish_cloud(f->result, index); !c && status)
      status = rt::Unexpected<rt::Error>{c.error()};
    live.pipeline->want_cloud(scan_publishing.cloud_reader());  // as publish_cloud found it
    results.release();
    if (status) {
      live.counts.add(Count::kPublished);
      if (live.settings.stop_after_scans > 0 &&
          live.counts.get(Count::kPublished) >= live.settings.stop_after_scans) {
        live.control.notify();  // the main thread ends the run
      }
    } else {
      live.counts.add(Count::kPublishErrors);
      if (!reported) {
        std::fprintf(stderr, "%s: DDS: %s\n", live.settings.name.c_str(),
                     status.error().message.c_str());
      }
      reported = true;
    }
  }
}

}  // namespace stac::runtime
