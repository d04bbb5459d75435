// The perception thread: each complete scan through the pipeline (deskew, segment, track,
// classify) into a result slot for the publisher. Sleeps until the receiver has a scan; swaps in
// a reloaded model between scans. Ends when the receiver has ended and every scan is taken.
#include "rt/clock.hpp"
#include "runtime/live.hpp"

namespace stac::runtime {
namespace {

// A sleep without a wake-up ends after this long (a look for a stop that came without one).
constexpr std::int64_t kWaitNs = 100'000'000;

}  // namespace

void perception_loop(Component::Live& live) noexcept {
  velodyne::ScanStream& stream = *live.stream;
  pipeline::ScanPipeline& pipeline = *live.pipeline;
  rt::SlotExchange<Frame>& results = *live.results;
  const ego::PoseHistory* poses = live.inputs.ins() ? &*live.history : nullptr;
  const std::int64_t classify_budget_ns = live.settings.run.classify_budget_ns;
  std::uint64_t incomplete = 0, packets_lost = 0, overflow = 0, classes_late = 0,
                classes_current = 0;
  for (;;) {
    ModelHandover& handover = live.model_handover;
    if (handover.ready.load(std::memory_order_acquire)) {  // between scans
      pipeline.classifier()->set_model(handover.incoming);
      handover.hash.store(handover.incoming_hash, std::memory_order_relaxed);
      handover.reloads.fetch_add(1, std::memory_order_relaxed);
      handover.ready.store(false, std::memory_order_release);
    }
    const std::uint32_t seen = live.scans_ready.generation();
    velodyne::Scan* scan = stream.take();
    if (scan == nullptr) {
      if (!live.receiver_done.load(std::memory_order_acquire)) {
        live.scans_ready.wait(seen, kWaitNs);
        continue;
      }
      if ((scan = stream.take()) == nullptr) break;
    }
    packets_lost += scan->header.packets_lost;
    live.counts.set(Count::kPacketsLost, packets_lost);
    if (!scan->header.complete()) {  // the first scan after start-up or a gap, or points dropped
      live.counts.set(Count::kIncomplete, ++incomplete);
      stream.release();
      continue;
    }
    Frame& f = results.current();
    f.started_ns = rt::realtime_ns();
    f.last_firing_ns = scan->header.end_stamp_ns;
    // Published tracks are classified until the scan is classify_budget old; the rest after.
    pipeline.process(*scan, poses, f.result, f.last_firing_ns + classify_budget_ns);
    classes_late += f.result.classes_late;
    classes_current += f.result.classes_current;
    const segmentation::SegmentCounters& c = f.result.segments.counters;
    overflow += c.ignored_over_capacity + c.dropped_cell_overflow + c.dropped_segment_overflow;
    f.segment_overflow = overflow;
    f.without_pose = pipeline.scans_without_pose();
    f.classes_late = classes_late;
    live.counts.set(Count::kClassesLate, classes_late);
    live.counts.set(Count::kClassesCurrent, classes_current);
    f.finished_ns = rt::realtime_ns();
    live.counts.add(Count::kScans);
    (void)results.publish();  // full: dropped and counted by the exchange; perception goes on
    live.results_ready.notify();
    pipeline.finish_scan(*scan);  // the other tracks and the accumulated clouds: off the latency
    stream.release();
  }
  live.perception_done.store(true, std::memory_order_release);
  live.results_ready.notify();
}

}  // namespace stac::runtime
