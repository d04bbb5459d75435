// The summary a run prints when it ends (docs/run.md "Summary").
#include <cstdio>

#include "runtime/component.hpp"

namespace stac::runtime {

void print_summary(const Summary& s, const std::string& name, std::FILE* out) {
  const auto u = [](std::uint64_t v) { return static_cast<unsigned long long>(v); };
  std::fprintf(out, "%s: stopped after %.1f s%s\n", name.c_str(), s.elapsed_s,
               s.stop_requested ? " (signal)" : "");
  std::fprintf(out,
               "  packets     %llu received, %llu dropped by the kernel, %llu truncated, %llu "
               "receive errors, %llu lost on the wire (estimated from azimuth steps)\n",
               u(s.received), u(s.kernel_drops), u(s.truncated), u(s.receive_errors),
               u(s.packets_lost));
  std::fprintf(out,
               "  dropped     wrong size %llu, invalid block %llu, duplicate %llu, late firings "
               "%llu (packets the decoder refused)\n",
               u(s.wrong_size), u(s.invalid_block), u(s.duplicates), u(s.late_firings));
  if (s.other_model > 0) {
    std::fprintf(out,
                 "  sensor      %llu packets name another model than velodyne.model: decoded as "
                 "configured (check velodyne.model; docs/velodyne.md)\n",
                 u(s.other_model));
  }
  std::fprintf(
      out,
      "  scans       %llu received (complete), %llu published, %llu incomplete (not processed), "
      "%llu of them with more packets lost than velodyne.min_scan_completeness %.2f allows\n",
      u(s.scans), u(s.published), u(s.incomplete), u(s.below_completeness), s.min_completeness);
  std::fprintf(out,
               "  drops       scan slots full %llu, result slots full %llu, DDS errors %llu, "
               "tracking pool full %llu, detections %llu\n",
               u(s.scan_slots_full), u(s.result_slots_full), u(s.publish_errors),
               u(s.pool_overflow), u(s.dropped_detections));
  if (s.has_model) {
    std::fprintf(out, "  model       %016llx, %u swapped in (SIGHUP), %llu refused\n",
                 u(s.model_hash), s.model_reloads, u(s.model_refused));
  }
  if (s.has_classifier) {
    std::fprintf(out,
                 "  classes     %llu published tracks classified before publication, %llu after "
                 "it (run.classify_budget_ms %.1f: their class one scan late)\n",
                 u(s.classes_current), u(s.classes_late), s.classify_budget_ms);
  }
  std::fprintf(out,
               "  ego         %llu INS fixes, %llu dead-reckoned poses, %llu scans without a "
               "pose\n",
               u(s.ins_fixes), u(s.dead_reckoned), u(s.without_pose));
  if (s.has_ins) {
    std::fprintf(out,
                 "  ins         %llu poses rejected, %llu fixes with impossible values, %llu time "
                 "jumps, %llu jumps back (a new timeline); input: bad "
                 "checksum %llu, bad framing %llu, malformed %llu, %llu bytes skipped; connect "
                 "failures %llu, disconnects %llu\n",
                 u(s.poses_rejected), u(s.ins_impossible), u(s.time_jumps), u(s.backward_jumps),
                 u(s.ins_bad_checksum), u(s.ins_bad_framing), u(s.ins_malformed),
                 u(s.ins_garbage_bytes), u(s.ins_connect_failures), u(s.ins_disconnects));
  }
  if (s.has_can) {
    const can::CanInputCounters& cc = s.can;
    std::fprintf(out,
                 "  can         %s: %llu frames, %llu with odometry, %llu not in the signal map; "
                 "drops: kernel %llu, adapter overflows %llu, ring full %llu, CAN FD %llu, "
                 "malformed %llu, other channel %llu, lost on the network %llu; read errors %llu\n",
                 s.can_description.c_str(), u(cc.frames), u(cc.updates), u(cc.not_mapped),
                 u(cc.kernel_drops), u(cc.overflows), u(s.can_ring_full), u(cc.can_fd),
                 u(cc.malformed), u(cc.other_channel), u(cc.lost), u(cc.read_errors));
  }
  std::fprintf(out, "  inputs     ");
  for (const Summary::Input& i : s.inputs)
    std::fprintf(out, " %s %s (%llu stalls)", i.name, i.state, u(i.stalls));
  std::fprintf(out, "\n  deadline    %.1f ms: %llu misses of %llu published scans\n", s.deadline_ms,
               u(s.deadline_misses), u(s.deadline_scans));
  std::fprintf(out, "  %-12s %9s %9s %9s   (ms, wall clock; histogram bins of 0.1 ms)\n", "latency",
               "p50", "p99", "max");
  for (const Summary::Latency& l : s.latencies) {
    std::fprintf(out, "  %-12s %9.3f %9.3f %9.3f\n", l.name, l.p50_ms, l.p99_ms, l.max_ms);
  }
}

}  // namespace stac::runtime
