// The classification evaluation job (class_eval_job.hpp): each track of the datasets through the
// model's filters, tallied as the thesis's Table 1.2, and the report written.
#include "offline/class_eval_job.hpp"

#include <algorithm>
#include <array>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <span>

#include "formats/dataset_file.hpp"
#include "formats/durable_file.hpp"
#include "formats/model_file.hpp"
#include "perception/classification/holistic.hpp"
#include "perception/classification/model.hpp"
#include "pictures/chart.hpp"
#include "pictures/drawing.hpp"
#include "rt/formatted.hpp"

namespace stac::offline {

using namespace stac::formats;
namespace {

using classification::ClassIndex;
using classification::ClassNames;
using classification::LogOdds;
constexpr std::size_t kMaxLabels = classification::kMaxClasses + 1;  // the classes, background

enum Filter : std::size_t {
  kAdbf,
  kNormalized,
  kNaive,
  kSegmentOnly,
  kHolisticOnly,
  kPriorOnly,
  kFilters
};
constexpr std::array<const char*, kFilters> kFilterNames = {
    "adbf", "normalized_dbf", "naive_dbf", "segment_only", "holistic_only", "prior_only"};

// Rows and columns 0..labels-1: the model's classes, then background (the last).
struct Tally {
  std::size_t labels = 0;
  std::array<std::array<std::uint64_t, kMaxLabels>, kMaxLabels> confusion{};  // [truth][predicted]
  [[nodiscard]] std::size_t row(ClassIndex c) const {
    return c == classification::kBackground ? labels - 1 : c;
  }
  void add(ClassIndex truth, ClassIndex predicted) { ++confusion[row(truth)][row(predicted)]; }
  [[nodiscard]] std::uint64_t total() const {
    std::uint64_t n = 0;
    for (const auto& row : confusion)
      for (std::uint64_t v : row) n += v;
    return n;
  }
  [[nodiscard]] double accuracy() const {
    std::uint64_t ok = 0;
    for (std::size_t i = 0; i < labels; ++i) ok += confusion[i][i];
    return total() == 0 ? 0.0 : static_cast<double>(ok) / static_cast<double>(total());
  }
  // 1-vs-all: the fraction where "is class c" is predicted right.
  [[nodiscard]] double one_vs_all(std::size_t c) const {
    std::uint64_t ok = 0;
    for (std::size_t i = 0; i < labels; ++i)
      for (std::size_t j = 0; j < labels; ++j)
        if ((i == c) == (j == c)) ok += confusion[i][j];
    return total() == 0 ? 0.0 : static_cast<double>(ok) / static_cast<double>(total());
  }
};

struct Scored {
  float score;  // the ADBF log odds of one class
  bool positive;
};

// Precision-recall points of one class by sweeping the threshold over the scores.
void pr_curve(std::vector<Scored> s, pictures::ChartSeries& out) {
  std::sort(s.begin(), s.end(), [](const Scored& a, const Scored& b) { return a.score > b.score; });
  std::size_t positives = 0;
  for (const Scored& x : s) positives += x.positive ? 1 : 0;
  if (positives == 0) return;
  std::size_t tp = 0;
  for (std::size_t i = 0; i < s.size(); ++i) {
    tp += s[i].positive ? 1 : 0;
    if (i + 1 < s.size() && s[i + 1].score == s[i].score) continue;
    out.x.push_back(static_cast<double>(tp) / static_cast<double>(positives));
    out.y.push_back(static_cast<double>(tp) / static_cast<double>(i + 1));
  }
}

rt::Status save_confusion(const Tally& t, const ClassNames& names, const std::string& title,
                          const std::filesystem::path& png) {
  std::vector<std::string> labels;
  std::vector<std::vector<std::uint64_t>> counts;
  for (std::size_t i = 0; i < t.labels; ++i) {
    labels.push_back(classification::class_name(
        names, i + 1 == t.labels ? classification::kBackground : static_cast<ClassIndex>(i)));
    counts.emplace_back(t.confusion[i].begin(),
                        t.confusion[i].begin() + static_cast<long>(t.labels));
  }
  return pictures::save_confusion_matrix(png, title, labels, counts);
}

}  // namespace

rt::Status run_class_eval_job(const ClassEvalJobOptions& o, const JobOutput& output) {
  auto model = read_model_file(o.model);
  if (!model) return rt::make_error(model.error().message);
  // Labels map by name onto the model's classes: each must be one of a dataset's, whose other
  // classes count as background (a model without `pole` scored on drives labelled with poles).
  const classification::TrackClassifierModel& m = *model;
  const ClassNames& names = m.classes;
  const std::size_t classes = names.size();
  Dataset data;
  data.classes = names;
  for (const std::string& dir : o.data) {
    auto d = read_labelled_dataset(dir, "stac eval --classes");
    if (!d) return rt::make_error(d.error().message);
    if (auto c = map_classes(*d, names, dir + " (for the classes of " + o.model + ")"); !c)
      return rt::make_error(c.error().message);
    if (auto a = append_dataset(data, std::move(*d), dir); !a)
      return rt::make_error(a.error().message);
  }
  if (data.tracks.empty())
    return rt::make_error("the datasets hold no track: nothing to evaluation::evaluate");
  const LogOdds prior = m.holistic.model().prior;
  const auto predict = [classes](const LogOdds& l) { return classification::predict(l, classes); };
  // The tables count consistent tracks (kMaxOffLabelFraction, the thesis's protocol); every
  // track, inconsistent ones too, is in all_tracks (ADBF) and in tracks.csv.
  std::array<Tally, kFilters> tracks{}, segments{};
  Tally all_tracks{};
  all_tracks.labels = classes + 1;
  for (std::size_t f = 0; f < kFilters; ++f) tracks[f].labels = segments[f].labels = classes + 1;
  std::array<std::vector<Scored>, classification::kMaxClasses> scores;
  const std::size_t sd = descriptors::kDimensions, hd = classification::kHolisticDimensions;
  // One line per track for the report (tracks.csv): where each wrong one came from.
  std::string per_track = "source,track_id,label,adbf_class,";
  for (const std::string& n : names) per_track += n + "_log_odds,";
  per_track += "segments,max_speed_mps,box_length_m,box_width_m,box_height_m,consistent\n";
  std::size_t done = 0;
  for (const DatasetTrack& t : data.tracks) {
    const bool counted = consistent(t);
    classification::TrackEvidence evidence;
    std::array<LogOdds, kFilters> out{};
    for (std::uint32_t k = 0; k < t.segments; ++k) {
      const std::span<const float> seg(t.segment_rows.data() + k * sd, sd);
      const std::span<const float> hol(t.holistic_rows.data() + k * hd, hd);
      LogOdds hs{}, hh{};
      if (!classification::add_segment(m, seg, evidence, hs) || !m.holistic.classify(hol, hh) ||
          !classification::track_log_odds(m, evidence, hol, out[kAdbf])) {
        return rt::make_error(
            "descriptor sizes differ from the model's (dataset and model of different builds?)");
      }
      out[kNormalized] = classification::normalized_dbf(evidence, hh);
      out[kNaive] = classification::naive_dbf(evidence, hh);
      out[kSegmentOnly] = hs;
      out[kHolisticOnly] = hh;
      out[kPriorOnly] = prior;
      if (counted) {
        for (std::size_t f = 0; f < kFilters; ++f) segments[f].add(t.label, predict(out[f]));
      }
    }
    all_tracks.add(t.label, predict(out[kAdbf]));
    if (counted) {
      for (std::size_t f = 0; f < kFilters; ++f) tracks[f].add(t.label, predict(out[f]));
    }
    if (t.segments > 0) {
      const float* last = t.holistic_rows.data() + (t.segments - 1) * hd;
      char field[128];
      std::snprintf(field, sizeof(field), "%u,%llu,", t.source,
                    static_cast<unsigned long long>(t.id));
      per_track += std::string(field) + classification::class_name(names, t.label) + "," +
                   classification::class_name(names, predict(out[kAdbf])) + ",";
      for (std::size_t c = 0; c < classes; ++c) {
        std::snprintf(field, sizeof(field), "%.3f,", static_cast<double>(out[kAdbf][c]));
        per_track += field;
      }
      std::snprintf(field, sizeof(field), "%u,%.2f,%.2f,%.2f,%.2f,%d\n", t.segments,
                    static_cast<double>(last[0]), static_cast<double>(last[6]),
                    static_cast<double>(last[7]), static_cast<double>(last[8]), counted ? 1 : 0);
      per_track += field;
    }
    for (std::size_t c = 0; c < classes && counted; ++c) {
      scores[c].push_back({out[kAdbf][c], t.label == c});
    }
    output.advance("eval: classifying", static_cast<double>(++done),
                   static_cast<double>(data.tracks.size()));
  }

  const std::uint64_t inconsistent = all_tracks.total() - tracks[kAdbf].total();
  nlohmann::json metrics = {{"track_accuracy", tracks[kAdbf].accuracy()},
                            {"segment_accuracy", segments[kAdbf].accuracy()},
                            {"tracks", tracks[kAdbf].total()},
                            {"segments", segments[kAdbf].total()},
                            {"inconsistent_tracks", inconsistent},
                            {"all_tracks.track_accuracy", all_tracks.accuracy()}};
  output.tell(rt::formatted(
      "stac eval --classes: %llu tracks, %llu segments (%llu inconsistent tracks left out); "
      "model %s\n",
      static_cast<unsigned long long>(tracks[kAdbf].total()),
      static_cast<unsigned long long>(segments[kAdbf].total()),
      static_cast<unsigned long long>(inconsistent), o.model.c_str()));
  output.tell(rt::formatted("%-8s %-15s", "", "filter"));
  for (const std::string& n : names)
    output.tell(rt::formatted(" %*s", std::max(9, static_cast<int>(n.size())), n.c_str()));
  output.tell(rt::formatted(" %8s\n", "overall"));
  for (int wise = 0; wise < 2; ++wise) {
    const auto& tallies = wise == 0 ? tracks : segments;
    const char* w = wise == 0 ? "track" : "segment";
    for (std::size_t f = 0; f < kFilters; ++f) {
      output.tell(rt::formatted("%-8s %-15s", w, kFilterNames[f]));
      for (std::size_t c = 0; c < classes; ++c) {
        const double a = tallies[f].one_vs_all(c);
        output.tell(rt::formatted(" %*.3f", std::max(9, static_cast<int>(names[c].size())), a));
        metrics[std::string(w) + "." + kFilterNames[f] + "." + names[c]] = a;
      }
      output.tell(rt::formatted(" %8.3f\n", tallies[f].accuracy()));
      metrics[std::string(w) + "." + kFilterNames[f] + ".overall"] = tallies[f].accuracy();
    }
  }
  output.tell(
      rt::formatted("every track, the inconsistent ones too: ADBF track-wise %.3f (%llu tracks)\n",
                    all_tracks.accuracy(), static_cast<unsigned long long>(all_tracks.total())));
  nlohmann::json confusion = nlohmann::json::array();
  for (std::size_t i = 0; i < tracks[kAdbf].labels; ++i) {
    const auto& row = tracks[kAdbf].confusion[i];
    confusion.push_back(std::vector<std::uint64_t>(row.begin(), row.begin() + classes + 1));
  }
  metrics["classes"] = names;
  metrics["track_confusion_adbf"] = confusion;

  if (!o.report.empty()) {
    const std::filesystem::path dir = o.report;
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    if (ec)
      return rt::make_error(o.report + ": cannot create the report folder (" + ec.message() + ")");
    if (auto w = formats::write_text_durably(dir / "metrics.json", metrics.dump(2) + "\n"); !w)
      return rt::make_error(w.error().message);
    if (auto w = formats::write_text_durably(dir / "tracks.csv", per_track); !w)
      return rt::make_error(w.error().message);
    if (auto r = save_confusion(tracks[kAdbf], names, "Track-wise confusion, ADBF",
                                dir / "confusion.png");
        !r) {
      return rt::make_error(r.error().message);
    }
    pictures::Chart chart{
        "Precision-recall, ADBF track-wise (1-vs-all)", "recall", "precision", {}, 800, 420};
    for (std::size_t c = 0; c < classes; ++c) {
      pictures::ChartSeries s{names[c], {}, {}};
      pr_curve(scores[c], s);
      if (!s.x.empty()) chart.series.push_back(std::move(s));
    }
    if (auto r = pictures::save_chart(chart, dir / "pr.png"); !r)
      return rt::make_error(r.error().message);
    output.tell(rt::formatted("report: %s/metrics.json, tracks.csv, confusion.png, pr.png\n",
                              o.report.c_str()));
  }
  return {};
}

}  // namespace stac::offline
