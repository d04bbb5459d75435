// The summary a run prints when it ends (docs/run.md "Summary").
#include <cstdio>
#include <nlohmann/json.hpp>

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

std::string summary_json(const Summary& s) {
  nlohmann::json latencies = nlohmann::json::array();
  for (const Summary::Latency& l : s.latencies)
    latencies.push_back(
        {{"stage", l.name}, {"p50_ms", l.p50_ms}, {"p99_ms", l.p99_ms}, {"max_ms", l.max_ms}});
  nlohmann::json inputs = nlohmann::json::array();
  for (const Summary::Input& i : s.inputs)
    if (i.name[0] != '\0')
      inputs.push_back({{"input", i.name}, {"state", i.state}, {"stalls", i.stalls}});
  nlohmann::json j = {
      {"elapsed_s", s.elapsed_s},
      {"stop_requested", s.stop_requested},
      {"packets",
       {{"received", s.received},
        {"kernel_drops", s.kernel_drops},
        {"truncated", s.truncated},
        {"receive_errors", s.receive_errors},
        {"lost", s.packets_lost},
        {"wrong_size", s.wrong_size},
        {"invalid_block", s.invalid_block},
        {"duplicates", s.duplicates},
        {"other_model", s.other_model},
        {"late_firings", s.late_firings}}},
      {"scans",
       {{"received", s.scans},
        {"published", s.published},
        {"incomplete", s.incomplete},
        {"below_completeness", s.below_completeness},
        {"min_completeness", s.min_completeness},
        {"scan_slots_full", s.scan_slots_full},
        {"result_slots_full", s.result_slots_full},
        {"publish_errors", s.publish_errors}}},
      {"tracks",
       {{"pool_overflow", s.pool_overflow}, {"dropped_detections", s.dropped_detections}}},
      {"model",
       {{"loaded", s.has_model},
        {"hash", s.model_hash},
        {"refused", s.model_refused},
        {"reloads", s.model_reloads}}},
      {"classes",
       {{"classifier", s.has_classifier},
        {"current", s.classes_current},
        {"late", s.classes_late},
        {"budget_ms", s.classify_budget_ms}}},
      {"ego",
       {{"ins", s.has_ins},
        {"ins_fixes", s.ins_fixes},
        {"dead_reckoned", s.dead_reckoned},
        {"without_pose", s.without_pose},
        {"poses_rejected", s.poses_rejected},
        {"ins_impossible", s.ins_impossible},
        {"time_jumps", s.time_jumps},
        {"backward_jumps", s.backward_jumps},
        {"ins_bad_checksum", s.ins_bad_checksum},
        {"ins_bad_framing", s.ins_bad_framing},
        {"ins_malformed", s.ins_malformed},
        {"ins_garbage_bytes", s.ins_garbage_bytes},
        {"ins_connect_failures", s.ins_connect_failures},
        {"ins_disconnects", s.ins_disconnects}}},
      {"can",
       {{"configured", s.has_can},
        {"description", s.can_description},
        {"frames", s.can.frames},
        {"updates", s.can.updates},
        {"not_mapped", s.can.not_mapped},
        {"kernel_drops", s.can.kernel_drops},
        {"overflows", s.can.overflows},
        {"can_fd", s.can.can_fd},
        {"malformed", s.can.malformed},
        {"lost", s.can.lost},
        {"other_channel", s.can.other_channel},
        {"read_errors", s.can.read_errors},
        {"ring_full", s.can_ring_full}}},
      {"inputs", inputs},
      {"deadline",
       {{"deadline_ms", s.deadline_ms},
        {"misses", s.deadline_misses},
        {"scans", s.deadline_scans}}},
      {"latencies", latencies}};
  return j.dump(2) + "\n";
}

}  // namespace stac::runtime
