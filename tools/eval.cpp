// stac eval: segmentation and tracking metrics of a tracks file against the simulator's truth,
// with a markdown report, metrics.json and plots. Definitions: docs/evaluation.md.
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
#include "tools/commands.hpp"
#include "tools/eval_classes.hpp"
#include "tools/support/progress.hpp"

namespace stac::tools {
namespace {

struct EvalOptions {
  std::string truth, tracks, report;
  std::string tracklets, drive, config_file;  // --tracklets: KITTI raw labels instead of --truth
  evaluation::EvalConfig config;
  bool classes = false;
  ClassEvalOptions class_options;
};

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

int write_report(const std::filesystem::path& dir, const evaluation::EvalResult& r,
                 const evaluation::EvalConfig& c, const EvalOptions& o, const std::string& frames) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) return fail(dir.string() + ": cannot create the report folder: " + ec.message());
  {
    nlohmann::json j = metrics_json(r, c);
    j["frames"] = frames;
    if (auto w = formats::write_text_durably(dir / "metrics.json", j.dump(2) + "\n"); !w)
      return fail(w.error().message);
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
    return fail(saved.error().message);
  }
  if (auto saved = pictures::save_bar_chart(
          dir / "classes.png", "Per class: recall, AssA, under- and over-segmentation", classes,
          {"recall", "AssA", "under-seg", "over-seg"}, class_values, 0.0);
      !saved) {
    return fail(saved.error().message);
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
    return fail(w.error().message);
  return 0;
}

int run_eval(const EvalOptions& o) {
  evaluation::EvalConfig c = o.config;
  c.classified_outputs_only = !o.tracklets.empty();
  if (!(c.max_range_m > 0)) return fail("--max-range must be positive");
  std::error_code ec;
  const double total = static_cast<double>(std::filesystem::file_size(o.truth, ec)) +
                       static_cast<double>(std::filesystem::file_size(o.tracks, ec));
  Progress progress("eval: reading", ec ? 0.0 : total);
  rt::Result<std::vector<evaluation::TruthScanRecord>> truth =
      std::vector<evaluation::TruthScanRecord>{};
  if (!o.tracklets.empty()) {
    // KITTI raw labels, placed in the world by their drive's poses (its folder by default).
    const std::filesystem::path drive = o.drive.empty()
                                            ? std::filesystem::path(o.tracklets).parent_path()
                                            : std::filesystem::path(o.drive);
    auto ego = settings::load_ego_settings(settings::config_path(o.config_file));
    if (!ego) return fail(ego.error().message);
    truth = evaluation::truth_from_tracklets(o.tracklets, drive.empty() ? "." : drive, *ego);
  } else {
    truth = evaluation::read_truth_file(
        o.truth, [&](std::uint64_t b) { progress.update(static_cast<double>(b)); });
  }
  if (!truth) return fail(truth.error().message);
  double done = ec ? 0.0 : static_cast<double>(std::filesystem::file_size(o.truth, ec));
  auto tracks = evaluation::read_tracks_file(
      o.tracks, [&](std::uint64_t b) { progress.update(done + static_cast<double>(b)); });
  if (!tracks) return fail(tracks.error().message);
  progress.finish();
  const std::string& truth_name = o.tracklets.empty() ? o.truth : o.tracklets;
  if (c.classified_outputs_only) {
    bool any = false;
    for (const evaluation::TracksScan& scan : *tracks)
      for (const evaluation::TrackRecord& t : scan.tracks) any = any || t.classified;
    if (!any)
      std::fprintf(stderr,
                   "stac eval: note: no track of %s carries a class, so none can be a false "
                   "positive against %s (KITTI labels no background); process with a model\n",
                   o.tracks.c_str(), truth_name.c_str());
  }
  if (truth->empty()) return fail(truth_name + ": no scans");
  // The truth in the tracks' frame, or a refusal that says what to do.
  auto frames = evaluation::truth_in_tracks_frame(*truth, *tracks);
  if (!frames) return fail(o.tracks + " against " + truth_name + ": " + frames.error().message);
  const evaluation::EvalResult r = evaluation::evaluate(*truth, *tracks, c);
  if (r.paired_scans == 0) {
    return fail("no scan of " + o.tracks + " matches a scan of " + truth_name +
                " by time: are they from the same run?");
  }
  std::printf("stac eval: %llu scans paired (truth %llu, output %llu)\n",
              static_cast<unsigned long long>(r.paired_scans),
              static_cast<unsigned long long>(r.truth_scans),
              static_cast<unsigned long long>(r.output_scans));
  std::printf("%s\n", frames->c_str());
  std::printf("%s", summary_table(r, c).c_str());
  if (!o.report.empty()) {
    if (const int code = write_report(o.report, r, c, o, *frames); code != 0) return code;
    std::printf("report: %s/report.md, metrics.json, range.png, classes.png\n", o.report.c_str());
  }
  return 0;
}

}  // namespace

void add_eval_command(CLI::App& app) {
  auto o = std::make_shared<EvalOptions>();
  CLI::App* cmd = app.add_subcommand(
      "eval",
      "Segmentation and tracking metrics (CLEAR MOT, HOTA) of a tracks file against the truth");
  cmd->add_option("--truth", o->truth,
                  "truth JSON lines written by `stac sim --truth` (required without --classes)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--tracklets", o->tracklets,
                  "instead of --truth: a KITTI raw drive's tracklet_labels.xml (Car, Van, Truck, "
                  "Tram -> car; Pedestrian, Person_sitting -> pedestrian; Cyclist -> bicyclist; "
                  "Misc and DontCare left out), placed in the world by the drive's poses")
      ->check(CLI::ExistingFile);
  cmd->add_option("--drive", o->drive,
                  "with --tracklets: the drive folder (default: the tracklets file's folder)")
      ->check(CLI::ExistingDirectory);
  cmd->add_option("--config", o->config_file,
                  std::string(stac::settings::kConfigOptionHelp) +
                      " (with --tracklets: the mounting when the drive has no "
                      "calib_imu_to_velo.txt)");
  cmd->add_option(
         "--tracks", o->tracks,
         "tracks JSON lines written by `stac process --tracks` (required without --classes)")
      ->check(CLI::ExistingFile);
  cmd->add_flag(
      "--classes", o->classes,
      "classification instead (thesis Table 1.2): needs --data and --model, not --truth/--tracks");
  cmd->add_option("--data", o->class_options.data,
                  "with --classes: a `stac dataset` folder (repeatable)");
  cmd->add_option("--model", o->class_options.model,
                  "with --classes: the model file of `stac train`");
  cmd->add_option("--report", o->report, "folder for report.md, metrics.json and the plots");
  cmd->add_option("--max-range", o->config.max_range_m,
                  "evaluate truth objects within this range of the ego (m)")
      ->capture_default_str();
  cmd->add_option("--min-points", o->config.min_points,
                  "evaluate truth objects with at least this many points")
      ->capture_default_str();
  cmd->add_flag("--with-coasting", o->config.count_coasting,
                "count coasting tracks (predicted, not updated in the scan) as outputs too");
  cmd->footer(
      "Metric definitions: docs/evaluation.md.\nExample:\n"
      "  stac eval --truth run.truth.jsonl --tracks run.tracks.jsonl --report eval/\n"
      "  stac eval --tracklets drive/tracklet_labels.xml --tracks drive.tracks.jsonl  # KITTI raw\n"
      "  stac eval --classes --data test/ --model model.stac --report cls/  # classification");
  cmd->callback([o] {
    int code = 0;
    if (o->classes) {
      if (!o->truth.empty() || !o->tracks.empty()) {
        code = fail(
            "--classes evaluates a classifier on --data and --model; --truth/--tracks are for "
            "tracking");
      } else if (o->class_options.data.empty() || o->class_options.model.empty()) {
        code = fail(
            "--classes needs --data DIR (a `stac dataset` folder) and --model MODEL (`stac train "
            "--out`)");
      } else {
        o->class_options.report = o->report;
        code = run_class_eval(o->class_options);
      }
    } else if (!o->truth.empty() && !o->tracklets.empty()) {
      code = fail("--truth or --tracklets, not both");
    } else if ((o->truth.empty() && o->tracklets.empty()) || o->tracks.empty()) {
      code = fail(
          "--truth (or --tracklets) and --tracks are required (or --classes with --data and "
          "--model)");
    } else if (!o->class_options.data.empty() || !o->class_options.model.empty()) {
      code = fail("--data and --model go with --classes");
    } else {
      code = run_eval(*o);
    }
    if (code != 0) throw CLI::RuntimeError(code);
  });
}

}  // namespace stac::tools
