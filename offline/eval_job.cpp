// The tracking evaluation job (eval_job.hpp): the truth (a simulator's, or KITTI tracklets placed
// by the drive's poses) and the tracks read, paired by time in one frame, evaluated
// (evaluation/evaluation.hpp), and the summary, markdown report, metrics.json and plots written.
#include "offline/eval_job.hpp"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "evaluation/evaluation.hpp"
#include "evaluation/frames.hpp"
#include "evaluation/tracklet_truth.hpp"
#include "formats/durable_file.hpp"
#include "pictures/drawing.hpp"
#include "rt/formatted.hpp"
#include "settings/settings.hpp"

namespace stac::offline {
namespace {

std::string band_name(int b, const evaluation::EvalConfig& c) {
  char buf[48];
  std::snprintf(buf, sizeof(buf), "%g-%g", b * c.range_band_m,
                std::min((b + 1) * c.range_band_m, c.max_range_m));
  return buf;
}

nlohmann::json clear_json(const evaluation::ClearCounts& k, bool with_fp) {
  nlohmann::json j = {{"gt", k.gt},
                      {"tp", k.tp},
                      {"fn", k.fn},
                      {"id_switches", k.id_switches},
                      {"fragmentations", k.fragmentations},
                      {"recall", k.recall()},
                      {"motp", k.motp()},
                      {"motp_distance_m", k.motp_distance_m()}};
  if (with_fp) {
    j["fp"] = k.fp;
    j["mota"] = k.mota();
  } else {
    j["mota_without_fp"] = k.mota();  // false positives not attributed by class (EvalResult)
  }
  return j;
}

nlohmann::json hota_json(const evaluation::HotaCounts& k, bool with_fp) {
  nlohmann::json j = {{"assa", k.assa()}, {"detre", k.detre()}, {"loca", k.loca()}};
  if (with_fp) {
    j["hota"] = k.hota();
    j["deta"] = k.deta();
  }
  return j;
}

nlohmann::json seg_json(const evaluation::SegCounts& k) {
  return {{"objects", k.objects},
          {"unsegmented", k.unsegmented},
          {"over", k.over},
          {"under", k.under},
          {"over_segmentation", k.over_rate()},
          {"under_segmentation", k.under_rate()}};
}

nlohmann::json metrics_json(const evaluation::EvalResult& r, const evaluation::EvalConfig& c) {
  nlohmann::json j;
  j["mota"] = r.clear.mota();
  j["motp"] = r.clear.motp();
  j["motp_distance_m"] = r.clear.motp_distance_m();
  j["id_switches"] = r.clear.id_switches;
  j["fragmentations"] = r.clear.fragmentations;
  j["false_positives"] = r.clear.fp;
  j["false_negatives"] = r.clear.fn;
  j["gt"] = r.clear.gt;
  j["hota"] = r.hota.hota();
  j["deta"] = r.hota.deta();
  j["assa"] = r.hota.assa();
  j["loca"] = r.hota.loca();
  if (r.has_segment_truth) {
    j["under_segmentation"] = r.segmentation.under_rate();
    j["over_segmentation"] = r.segmentation.over_rate();
  } else {
    j["under_segmentation"] = nullptr;  // the tracks file carries no truth composition
    j["over_segmentation"] = nullptr;
  }
  j["scans"] = {{"truth", r.truth_scans}, {"output", r.output_scans}, {"paired", r.paired_scans}};
  j["ignored_track_scans"] = r.ignored_tracks;
  for (const auto& [cls, k] : r.clear_by_class) {
    j["by_class"][cls] = clear_json(k, r.fp_by_class);
    j["by_class"][cls].update(hota_json(r.hota_by_class.at(cls), r.fp_by_class));
  }
  for (const auto& [b, k] : r.clear_by_band) {
    j["by_range"][band_name(b, c)] = clear_json(k, true);
    if (r.hota_by_band.count(b) != 0)
      j["by_range"][band_name(b, c)].update(hota_json(r.hota_by_band.at(b), true));
  }
  if (r.has_segment_truth) {
    for (const auto& [cls, k] : r.segmentation_by_class)
      j["segmentation_by_class"][cls] = seg_json(k);
    for (const auto& [b, k] : r.segmentation_by_band)
      j["segmentation_by_range"][band_name(b, c)] = seg_json(k);
  }
  j["config"] = {{"max_range_m", c.max_range_m},           {"min_points", c.min_points},
                 {"range_band_m", c.range_band_m},         {"count_coasting", c.count_coasting},
                 {"piece_share", c.piece_share},           {"foreign_share", c.foreign_share},
                 {"under_min_points", c.under_min_points}, {"zero_distance_m", c.zero_distance_m}};
  return j;
}

std::string fmt(double v) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.3f", v);
  return buf;
}

std::string summary_table(const evaluation::EvalResult& r, const evaluation::EvalConfig& c) {
  std::ostringstream s;
  s << "| group | GT | TP | FN | FP | IDSW | Frag | MOTA | MOTP | HOTA | AssA | under-seg | "
       "over-seg |\n"
    << "|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  auto seg = [&](const evaluation::SegCounts* k) {
    if (!r.has_segment_truth || k == nullptr) return std::string("n/a | n/a");
    return fmt(k->under_rate()) + " | " + fmt(k->over_rate());
  };
  s << "| all | " << r.clear.gt << " | " << r.clear.tp << " | " << r.clear.fn << " | " << r.clear.fp
    << " | " << r.clear.id_switches << " | " << r.clear.fragmentations << " | "
    << fmt(r.clear.mota()) << " | " << fmt(r.clear.motp()) << " | " << fmt(r.hota.hota()) << " | "
    << fmt(r.hota.assa()) << " | " << seg(&r.segmentation) << " |\n";
  for (const auto& [cls, k] : r.clear_by_class) {
    const auto sk = r.segmentation_by_class.find(cls);
    const evaluation::HotaCounts& hk = r.hota_by_class.at(cls);
    s << "| " << cls << " | " << k.gt << " | " << k.tp << " | " << k.fn << " | "
      << (r.fp_by_class ? std::to_string(k.fp) : std::string("-")) << " | " << k.id_switches
      << " | " << k.fragmentations << " | " << fmt(k.mota()) << (r.fp_by_class ? "" : "*") << " | "
      << fmt(k.motp()) << " | " << (r.fp_by_class ? fmt(hk.hota()) : std::string("-")) << " | "
      << fmt(hk.assa()) << " | " << seg(sk == r.segmentation_by_class.end() ? nullptr : &sk->second)
      << " |\n";
  }
  for (const auto& [b, k] : r.clear_by_band) {
    const auto sk = r.segmentation_by_band.find(b);
    const auto hk = r.hota_by_band.find(b);
    s << "| " << band_name(b, c) << " m | " << k.gt << " | " << k.tp << " | " << k.fn << " | "
      << k.fp << " | " << k.id_switches << " | " << k.fragmentations << " | " << fmt(k.mota())
      << " | " << fmt(k.motp()) << " | "
      << (hk == r.hota_by_band.end() ? "-" : fmt(hk->second.hota())) << " | "
      << (hk == r.hota_by_band.end() ? "-" : fmt(hk->second.assa())) << " | "
      << seg(sk == r.segmentation_by_band.end() ? nullptr : &sk->second) << " |\n";
  }
  if (r.fp_by_class) {
    s << "\nPer class: a false positive counts against the class its track was given (every "
         "track scored is classified as an evaluated class).\n";
  } else {
    s << "\n*per class: MOTA without false positives: every track is scored, classified or not, "
         "and an unclassified track's false positive belongs to no class (--tracklets scores "
         "classified tracks only, and counts their false positives by class).\n";
  }
  return s.str();
}

rt::Status write_report(const std::filesystem::path& dir, const evaluation::EvalResult& r,
                        const evaluation::EvalConfig& c, const EvalJobOptions& o,
                        const std::string& frames) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec)
    return rt::make_error(dir.string() + ": cannot create the report folder: " + ec.message());
  {
    nlohmann::json j = metrics_json(r, c);
    j["frames"] = frames;
    if (auto w = formats::write_text_durably(dir / "metrics.json", j.dump(2) + "\n"); !w)
      return rt::make_error(w.error().message);
  }
  std::vector<std::string> bands;
  std::vector<std::vector<double>> band_values(2);
  for (const auto& [b, k] : r.clear_by_band) {
    bands.push_back(band_name(b, c) + " m");
    band_values[0].push_back(k.mota());
    const auto hk = r.hota_by_band.find(b);
    band_values[1].push_back(hk == r.hota_by_band.end() ? NAN : hk->second.hota());
  }
  std::vector<std::string> classes;
  std::vector<std::vector<double>> class_values(4);
  for (const auto& [cls, k] : r.clear_by_class) {
    classes.push_back(cls);
    class_values[0].push_back(k.recall());
    class_values[1].push_back(r.hota_by_class.at(cls).assa());
    const auto sk = r.segmentation_by_class.find(cls);
    const bool seg = r.has_segment_truth && sk != r.segmentation_by_class.end();
    class_values[2].push_back(seg ? sk->second.under_rate() : NAN);
    class_values[3].push_back(seg ? sk->second.over_rate() : NAN);
  }
  if (auto saved = pictures::save_bar_chart(dir / "range.png", "MOTA and HOTA by range band", bands,
                                            {"MOTA", "HOTA"}, band_values, 0.0);
      !saved) {
    return rt::make_error(saved.error().message);
  }
  if (auto saved = pictures::save_bar_chart(
          dir / "classes.png", "Per class: recall, AssA, under- and over-segmentation", classes,
          {"recall", "AssA", "under-seg", "over-seg"}, class_values, 0.0);
      !saved) {
    return rt::make_error(saved.error().message);
  }
  std::ostringstream md;
  md << "# STAC evaluation\n\n"
     << "- truth: `" << (o.tracklets.empty() ? o.truth : o.tracklets) << "` (" << r.truth_scans
     << " scans)\n"
     << "- tracks: `" << o.tracks << "` (" << r.output_scans << " scans, " << r.paired_scans
     << " paired by time)\n"
     << "- " << frames << "\n"
     << "- evaluated: car, pedestrian, bicyclist within " << c.max_range_m
     << " m of the ego with at least " << c.min_points << " points; " << r.ignored_tracks
     << " track-scans ignored (on background, unevaluated truth, or out of range); outputs: "
        "confirmed"
     << (c.count_coasting ? " and coasting" : "") << " tracks\n"
     << "- definitions: docs/evaluation.md\n\n"
     << "## Summary\n\n"
     << "MOTA " << fmt(r.clear.mota()) << ", MOTP " << fmt(r.clear.motp()) << " (mean distance "
     << fmt(r.clear.motp_distance_m()) << " m), HOTA " << fmt(r.hota.hota()) << " (DetA "
     << fmt(r.hota.deta()) << ", AssA " << fmt(r.hota.assa()) << ", LocA " << fmt(r.hota.loca())
     << "), ID switches " << r.clear.id_switches << ", fragmentations " << r.clear.fragmentations
     << ".\n\n";
  if (r.has_segment_truth) {
    md << "Segmentation (car, pedestrian, bicyclist): under " << fmt(r.segmentation.under_rate())
       << ", over " << fmt(r.segmentation.over_rate()) << " of " << r.segmentation.objects
       << " object-scans (" << r.segmentation.unsegmented << " with no segmented point).\n\n";
  } else {
    md << "Segmentation: not evaluated (the tracks file's segments carry no truth "
          "composition).\n\n";
  }
  md << summary_table(r, c) << "\n";
  if (r.has_segment_truth) {
    md << "## Segmentation by class (background classes included)\n\n| class | object-scans | "
          "unsegmented | "
          "under | over |\n|---|---|---|---|---|\n";
    for (const auto& [cls, k] : r.segmentation_by_class) {
      md << "| " << cls << " | " << k.objects << " | " << k.unsegmented << " | "
         << fmt(k.under_rate()) << " | " << fmt(k.over_rate()) << " |\n";
    }
    md << "\n";
  }
  md << "![MOTA and HOTA by range](range.png)\n\n![Per class](classes.png)\n";
  if (auto w = formats::write_text_durably(dir / "report.md", md.str()); !w)
    return rt::make_error(w.error().message);
  return {};
}

}  // namespace

rt::Status run_eval_job(const EvalJobOptions& o, const JobOutput& out) {
  evaluation::EvalConfig c = o.config;
  c.classified_outputs_only = !o.tracklets.empty();
  if (!(c.max_range_m > 0)) return rt::make_error("--max-range must be positive");
  std::error_code ec;
  const double total = static_cast<double>(std::filesystem::file_size(o.truth, ec)) +
                       static_cast<double>(std::filesystem::file_size(o.tracks, ec));
  rt::Result<std::vector<evaluation::TruthScanRecord>> truth =
      std::vector<evaluation::TruthScanRecord>{};
  if (!o.tracklets.empty()) {
    // KITTI raw labels, placed in the world by their drive's poses (its folder by default).
    const std::filesystem::path drive = o.drive.empty()
                                            ? std::filesystem::path(o.tracklets).parent_path()
                                            : std::filesystem::path(o.drive);
    auto ego = settings::load_ego_settings(settings::config_path(o.config_file));
    if (!ego) return rt::make_error(ego.error().message);
    truth = evaluation::truth_from_tracklets(o.tracklets, drive.empty() ? "." : drive, *ego);
  } else {
    truth = evaluation::read_truth_file(o.truth, [&](std::uint64_t b) {
      out.advance("eval: reading", static_cast<double>(b), total);
    });
  }
  if (!truth) return rt::make_error(truth.error().message);
  double done = ec ? 0.0 : static_cast<double>(std::filesystem::file_size(o.truth, ec));
  auto tracks = evaluation::read_tracks_file(o.tracks, [&](std::uint64_t b) {
    out.advance("eval: reading", done + static_cast<double>(b), total);
  });
  if (!tracks) return rt::make_error(tracks.error().message);
  const std::string& truth_name = o.tracklets.empty() ? o.truth : o.tracklets;
  if (c.classified_outputs_only) {
    bool any = false;
    for (const evaluation::TracksScan& scan : *tracks)
      for (const evaluation::TrackRecord& t : scan.tracks) any = any || t.classified;
    if (!any)
      out.say(
          rt::formatted("stac eval: note: no track of %s carries a class, so none can be a false "
                        "positive against %s (KITTI labels no background); process with a model\n",
                        o.tracks.c_str(), truth_name.c_str()));
  }
  if (truth->empty()) return rt::make_error(truth_name + ": no scans");
  // The truth in the tracks' frame, or a refusal that says what to do.
  auto frames = evaluation::truth_in_tracks_frame(*truth, *tracks);
  if (!frames)
    return rt::make_error(o.tracks + " against " + truth_name + ": " + frames.error().message);
  const evaluation::EvalResult r = evaluation::evaluate(*truth, *tracks, c);
  if (r.paired_scans == 0) {
    return rt::make_error("no scan of " + o.tracks + " matches a scan of " + truth_name +
                          " by time: are they from the same run?");
  }
  out.tell(rt::formatted("stac eval: %llu scans paired (truth %llu, output %llu)\n",
                         static_cast<unsigned long long>(r.paired_scans),
                         static_cast<unsigned long long>(r.truth_scans),
                         static_cast<unsigned long long>(r.output_scans)));
  out.tell(rt::formatted("%s\n", frames->c_str()));
  out.tell(rt::formatted("%s", summary_table(r, c).c_str()));
  if (!o.report.empty()) {
    if (auto w = write_report(o.report, r, c, o, *frames); !w) return w;
    out.tell(rt::formatted("report: %s/report.md, metrics.json, range.png, classes.png\n",
                           o.report.c_str()));
  }
  return {};
}

}  // namespace stac::offline
