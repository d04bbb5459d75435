#include "evaluation/evaluation.hpp"

#include <algorithm>
#include <cmath>
#include <unordered_map>

#include "perception/tracking/assignment.hpp"

namespace stac::evaluation {
namespace {

constexpr double kForbidden = 1e9;
constexpr double kEps = 1e-9;
constexpr double kMatchSimilarity = 0.5;  // CLEAR MOT: d <= zero_distance / 2
constexpr double kBackgroundMarginM = 0.5;

double alpha(int a) {
  return 0.05 * (a + 1);
}

double range_of(double x, double y, const EgoRecord& ego) {
  return std::hypot(x - ego.x, y - ego.y);
}

bool inside_box_xy(const TruthObjectRecord& o, double x, double y, double margin) {
  const double c = std::cos(o.yaw), s = std::sin(o.yaw);
  const double dx = x - o.x, dy = y - o.y;
  const double u = c * dx + s * dy, v = -s * dx + c * dy;
  return std::abs(u) <= o.length / 2 + margin && std::abs(v) <= o.width / 2 + margin;
}

// One paired scan, as the tracking metrics need it.
struct Frame {
  std::vector<std::uint32_t> gt;      // compact gt indices
  std::vector<std::uint32_t> trk;     // compact track indices
  std::vector<double> sim;            // gt x trk
  std::vector<double> dist;           // gt x trk (m)
  std::vector<std::string> gt_class;  // per gt entry
  // Per track entry: its class when false positives are attributed by class (every output is
  // then classified as an evaluated class: classified_outputs_only), else empty.
  std::vector<std::string> trk_class;
  std::vector<int> gt_band, trk_band;
};

class Matcher {
 public:
  Matcher() : solver_(4096, 4096) {}
  // Maximises the sum of score over pairs with allowed[i*cols+j]; returns row -> col or -1.
  std::vector<int> maximise(const std::vector<double>& score, const std::vector<bool>& allowed,
                            std::size_t rows, std::size_t cols) {
    std::vector<int> out(rows, -1);
    if (rows == 0 || cols == 0) return out;
    std::vector<double> cost(rows * cols);
    for (std::size_t k = 0; k < cost.size(); ++k) cost[k] = allowed[k] ? -score[k] : kForbidden;
    if (!solver_.solve(cost, rows, cols, out)) {
      // Larger than the workspace (thousands of objects in one scan): fall back to nothing.
      std::fill(out.begin(), out.end(), -1);
      return out;
    }
    for (std::size_t i = 0; i < rows; ++i) {
      if (out[i] >= 0 && !allowed[i * cols + static_cast<std::size_t>(out[i])]) out[i] = -1;
    }
    return out;
  }

 private:
  tracking::AssignmentSolver solver_;
};

int band_of(double range, const EvalConfig& c) {
  const int last = std::max(0, static_cast<int>(std::ceil(c.max_range_m / c.range_band_m)) - 1);
  return std::clamp(static_cast<int>(range / c.range_band_m), 0, last);
}

void segmentation_of_scan(const TruthScanRecord& truth, const TracksScan& out, const EvalConfig& c,
                          EvalResult& r) {
  // Per truth id: (segment index, points of that object in it).
  std::unordered_map<std::int64_t, std::vector<std::pair<std::size_t, std::uint32_t>>> pieces;
  for (std::size_t s = 0; s < out.segments.size(); ++s) {
    for (const auto& [id, n] : out.segments[s].truth) {
      if (id >= 0 && n > 0) pieces[id].emplace_back(s, n);
    }
  }
  for (const TruthObjectRecord& o : truth.objects) {
    const double range = range_of(o.x, o.y, truth.ego);
    if (range > c.max_range_m || o.points < c.min_points) continue;
    const bool tracked = is_tracked_class(c, o.cls);
    SegCounts* counts[3] = {&r.segmentation_by_class[o.cls], tracked ? &r.segmentation : nullptr,
                            tracked ? &r.segmentation_by_band[band_of(range, c)] : nullptr};
    const auto it = pieces.find(o.id);
    std::uint64_t total = 0;
    if (it != pieces.end()) {
      for (const auto& p : it->second) total += p.second;
    }
    if (total == 0) {
      for (SegCounts* k : counts) {
        if (k != nullptr) ++k->unsegmented;
      }
      continue;
    }
    int piece_count = 0;
    bool under = false;
    for (const auto& [s, n] : it->second) {
      if (static_cast<double>(n) < c.piece_share * static_cast<double>(total)) continue;
      ++piece_count;
      std::uint64_t foreign = 0;
      for (const auto& [id, m] : out.segments[s].truth) {
        if (id >= 0 && id != static_cast<std::int64_t>(o.id)) foreign += m;
      }
      if (foreign >= c.under_min_points && static_cast<double>(foreign) > c.foreign_share * n)
        under = true;
    }
    for (SegCounts* k : counts) {
      if (k == nullptr) continue;
      ++k->objects;
      if (piece_count >= 2) ++k->over;
      if (under) ++k->under;
    }
  }
}

using ScanPair = std::pair<const TruthScanRecord*, const TracksScan*>;

// Pair scans by time: each output scan with the nearest truth scan within the tolerance, or
// the one whose sweep holds its time (a scan placed at one instant of its sweep, as KITTI's
// mid-sweep times are).
std::vector<ScanPair> pair_scans(const std::vector<TruthScanRecord>& truth_in,
                                 const std::vector<TracksScan>& tracks_in, const EvalConfig& c) {
  std::vector<const TruthScanRecord*> truth;
  truth.reserve(truth_in.size());
  for (const auto& t : truth_in) truth.push_back(&t);
  std::sort(truth.begin(), truth.end(), [](auto* a, auto* b) { return a->stamp_ns < b->stamp_ns; });
  std::vector<const TracksScan*> outputs;
  outputs.reserve(tracks_in.size());
  for (const auto& o : tracks_in) outputs.push_back(&o);
  std::stable_sort(outputs.begin(), outputs.end(),
                   [](auto* a, auto* b) { return a->stamp_ns < b->stamp_ns; });
  const auto tolerance_ns = static_cast<std::int64_t>(c.max_time_offset_s * 1e9);
  std::vector<ScanPair> pairs;
  const TruthScanRecord* last_used = nullptr;
  for (const TracksScan* o : outputs) {
    auto it = std::lower_bound(truth.begin(), truth.end(), o->stamp_ns,
                               [](auto* t, std::int64_t ns) { return t->stamp_ns < ns; });
    const TruthScanRecord* best = nullptr;
    for (auto cand : {it, it == truth.begin() ? truth.end() : it - 1}) {
      if (cand == truth.end()) continue;
      const std::int64_t off = std::llabs((*cand)->stamp_ns - o->stamp_ns);
      const bool in_sweep = (*cand)->end_stamp_ns > (*cand)->stamp_ns &&
                            o->stamp_ns >= (*cand)->stamp_ns &&
                            o->stamp_ns <= (*cand)->end_stamp_ns;
      if ((off <= tolerance_ns || in_sweep) &&
          (best == nullptr || off < std::llabs(best->stamp_ns - o->stamp_ns)))
        best = *cand;
    }
    if (best == nullptr || best == last_used) continue;  // no truth, or a duplicate output scan
    last_used = best;
    pairs.emplace_back(best, o);
  }
  return pairs;
}

double similarity(const TruthObjectRecord& g, const TrackRecord& t, const EvalConfig& c,
                  double* d_out) {
  const double d = std::hypot(g.x - t.x, g.y - t.y);
  if (d_out != nullptr) *d_out = d;
  return std::max(0.0, 1.0 - d / c.zero_distance_m.at(g.cls));
}

// The truth of one scan: evaluated objects first (`evaluated` of them), then distractors
// (tracked classes, not evaluated).
std::vector<const TruthObjectRecord*> truth_objects(const TruthScanRecord& ts, const EvalConfig& c,
                                                    std::size_t& evaluated) {
  std::vector<const TruthObjectRecord*> gts;
  for (int pass = 0; pass < 2; ++pass) {
    for (const TruthObjectRecord& o : ts.objects) {
      if (!is_tracked_class(c, o.cls)) continue;
      const bool eval = range_of(o.x, o.y, ts.ego) <= c.max_range_m && o.points >= c.min_points;
      if (eval == (pass == 0)) gts.push_back(&o);
    }
    if (pass == 0) evaluated = gts.size();
  }
  return gts;
}

// The truth objects and the output of one scan, for the preprocessing.
struct ScanTruth {
  const TruthScanRecord& ts;
  std::vector<const TruthObjectRecord*> gts;
  std::size_t evaluated = 0;
  std::unordered_map<std::int64_t, const TruthObjectRecord*> by_id;
  std::unordered_map<std::uint32_t, const SegmentRecord*> segment_by_id;
};

// An output matched to no truth object is ignored when out of range, unclassified (when only
// classified outputs count), on background, or on a segment mostly of background or of an
// unevaluated object.
bool ignored_unmatched(const TrackRecord& t, const ScanTruth& s, const EvalConfig& c) {
  bool ignore = range_of(t.x, t.y, s.ts.ego) > c.max_range_m ||
                (c.classified_outputs_only && !(t.classified && is_tracked_class(c, t.cls)));
  for (const TruthObjectRecord& o : s.ts.objects) {
    if (!is_tracked_class(c, o.cls) && inside_box_xy(o, t.x, t.y, kBackgroundMarginM))
      ignore = true;
  }
  if (const auto seg = s.segment_by_id.find(static_cast<std::uint32_t>(t.segment));
      t.segment >= 0 && seg != s.segment_by_id.end() && !seg->second->truth.empty()) {
    const auto major = std::max_element(seg->second->truth.begin(), seg->second->truth.end(),
                                        [](auto& a, auto& b) { return a.second < b.second; });
    const auto o = s.by_id.find(major->first);
    if (o != s.by_id.end()) {
      const auto g = std::find(s.gts.begin(), s.gts.end(), o->second);
      const bool evaluated_gt =
          g != s.gts.end() && static_cast<std::size_t>(g - s.gts.begin()) < s.evaluated;
      if (!evaluated_gt) ignore = true;  // mostly background or an unevaluated object
    }
  }
  return ignore;
}

// Preprocessing: drop tracks on unevaluated truth, on background, or out of range.
std::vector<const TrackRecord*> kept_tracks(const ScanTruth& s, const TracksScan& os,
                                            const EvalConfig& c, Matcher& matcher, EvalResult& r) {
  std::vector<const TrackRecord*> cands;
  for (const TrackRecord& t : os.tracks) {
    if (t.state == "confirmed" || (c.count_coasting && t.state == "coasting")) cands.push_back(&t);
  }
  const std::vector<const TruthObjectRecord*>& gts = s.gts;
  std::vector<double> score(cands.size() * gts.size());
  std::vector<bool> allowed(score.size());
  for (std::size_t i = 0; i < cands.size(); ++i) {
    for (std::size_t j = 0; j < gts.size(); ++j) {
      score[i * gts.size() + j] = similarity(*gts[j], *cands[i], c, nullptr);
      allowed[i * gts.size() + j] = score[i * gts.size() + j] >= kMatchSimilarity - kEps;
    }
  }
  const std::vector<int> pre = matcher.maximise(score, allowed, cands.size(), gts.size());
  std::vector<const TrackRecord*> kept;
  for (std::size_t i = 0; i < cands.size(); ++i) {
    const TrackRecord& t = *cands[i];
    if (pre[i] >= 0) {
      if (static_cast<std::size_t>(pre[i]) < s.evaluated)
        kept.push_back(&t);
      else
        ++r.ignored_tracks;  // on a distractor
      continue;
    }
    if (ignored_unmatched(t, s, c))
      ++r.ignored_tracks;
    else
      kept.push_back(&t);
  }
  return kept;
}

// The paired scans as the tracking metrics need them; truth and track ids made compact.
struct Frames {
  std::vector<Frame> frames;
  std::unordered_map<std::uint32_t, std::uint32_t> gt_index;
  std::unordered_map<std::uint64_t, std::uint32_t> trk_index;
};

// One paired scan's frame from its evaluated truth objects and kept tracks.
Frame frame_of(const ScanTruth& s, const std::vector<const TrackRecord*>& kept, const EvalConfig& c,
               Frames& all) {
  Frame f;
  for (std::size_t j = 0; j < s.evaluated; ++j) {
    const auto [it, fresh] =
        all.gt_index.try_emplace(s.gts[j]->id, static_cast<std::uint32_t>(all.gt_index.size()));
    f.gt.push_back(it->second);
    f.gt_class.push_back(s.gts[j]->cls);
    f.gt_band.push_back(band_of(range_of(s.gts[j]->x, s.gts[j]->y, s.ts.ego), c));
  }
  for (const TrackRecord* t : kept) {
    const auto [it, fresh] =
        all.trk_index.try_emplace(t->id, static_cast<std::uint32_t>(all.trk_index.size()));
    f.trk.push_back(it->second);
    f.trk_band.push_back(band_of(range_of(t->x, t->y, s.ts.ego), c));
    f.trk_class.push_back(c.classified_outputs_only && t->classified && is_tracked_class(c, t->cls)
                              ? t->cls
                              : std::string());
  }
  f.sim.resize(s.evaluated * kept.size());
  f.dist.resize(f.sim.size());
  for (std::size_t j = 0; j < s.evaluated; ++j) {
    for (std::size_t i = 0; i < kept.size(); ++i) {
      f.sim[j * kept.size() + i] = similarity(*s.gts[j], *kept[i], c, &f.dist[j * kept.size() + i]);
    }
  }
  return f;
}

// Per paired scan: its segmentation counts (when the output has segment truth) and its frame.
Frames frames_of(const std::vector<ScanPair>& pairs, const EvalConfig& c, Matcher& matcher,
                 EvalResult& r) {
  Frames all;
  all.frames.reserve(pairs.size());
  for (const auto& [ts, os] : pairs) {
    if (!os->segments.empty() && os->segments.front().has_truth) r.has_segment_truth = true;
    if (r.has_segment_truth) segmentation_of_scan(*ts, *os, c, r);
    ScanTruth s{*ts, {}, 0, {}, {}};
    s.gts = truth_objects(*ts, c, s.evaluated);
    for (const TruthObjectRecord& o : ts->objects) s.by_id[o.id] = &o;
    for (const SegmentRecord& seg : os->segments) s.segment_by_id[seg.id] = &seg;
    const std::vector<const TrackRecord*> kept = kept_tracks(s, *os, c, matcher, r);
    all.frames.push_back(frame_of(s, kept, c, all));
  }
  return all;
}

// CLEAR MOT's memory across scans, per compact truth id.
struct ClearHistory {
  explicit ClearHistory(std::size_t ngt)
      : previous(ngt, -1),
        last_ever(ngt, -1),
        tracked_before(ngt, false),
        interrupted(ngt, false) {}
  std::vector<std::int64_t> previous, last_ever;
  std::vector<bool> tracked_before, interrupted;
};

// Per truth entry its track entry or -1: the previous scan's matches that are still valid,
// then the best assignment of the rest.
std::vector<int> clear_matches(const Frame& f, const ClearHistory& h, Matcher& matcher) {
  const std::size_t ng = f.gt.size(), nt = f.trk.size();
  std::vector<int> match(ng, -1);
  std::vector<bool> trk_taken(nt, false);
  for (std::size_t j = 0; j < ng; ++j) {  // matches of the previous scan that are still valid
    if (h.previous[f.gt[j]] < 0) continue;
    for (std::size_t i = 0; i < nt; ++i) {
      if (f.trk[i] == h.previous[f.gt[j]] && f.sim[j * nt + i] >= kMatchSimilarity - kEps) {
        match[j] = static_cast<int>(i);
        trk_taken[i] = true;
      }
    }
  }
  std::vector<double> score(ng * nt);
  std::vector<bool> allowed(ng * nt);
  for (std::size_t j = 0; j < ng; ++j) {
    for (std::size_t i = 0; i < nt; ++i) {
      score[j * nt + i] = f.sim[j * nt + i];
      allowed[j * nt + i] =
          match[j] < 0 && !trk_taken[i] && f.sim[j * nt + i] >= kMatchSimilarity - kEps;
    }
  }
  const std::vector<int> fresh = matcher.maximise(score, allowed, ng, nt);
  for (std::size_t j = 0; j < ng; ++j) {
    if (match[j] < 0) match[j] = fresh[j];
  }
  return match;
}

// One scan's CLEAR MOT counts from its matches.
void count_clear(const Frame& f, const std::vector<int>& match, ClearHistory& h, EvalResult& r) {
  const std::size_t ng = f.gt.size(), nt = f.trk.size();
  std::vector<bool> trk_matched(nt, false);
  for (std::size_t j = 0; j < ng; ++j) {
    const std::uint32_t g = f.gt[j];
    ClearCounts* counts[3] = {&r.clear, &r.clear_by_class[f.gt_class[j]],
                              &r.clear_by_band[f.gt_band[j]]};
    for (ClearCounts* k : counts) ++k->gt;
    if (match[j] < 0) {
      for (ClearCounts* k : counts) ++k->fn;
      if (h.tracked_before[g]) h.interrupted[g] = true;
      h.previous[g] = -1;
      continue;
    }
    const auto i = static_cast<std::size_t>(match[j]);
    trk_matched[i] = true;
    const bool switched = h.last_ever[g] >= 0 && h.last_ever[g] != f.trk[i];
    for (ClearCounts* k : counts) {
      ++k->tp;
      k->similarity_sum += f.sim[j * nt + i];
      k->distance_sum_m += f.dist[j * nt + i];
      if (switched) ++k->id_switches;
      if (h.interrupted[g]) ++k->fragmentations;
    }
    h.interrupted[g] = false;
    h.tracked_before[g] = true;
    h.previous[g] = h.last_ever[g] = f.trk[i];
  }
  // Outputs left unmatched are false positives (a truth object absent from a scan keeps its
  // previous match for the next scan it appears in).
  for (std::size_t i = 0; i < nt; ++i) {
    if (trk_matched[i]) continue;
    ++r.clear.fp;
    ++r.clear_by_band[f.trk_band[i]].fp;
    if (!f.trk_class[i].empty()) ++r.clear_by_class[f.trk_class[i]].fp;
  }
}

void clear_mot(const Frames& all, Matcher& matcher, EvalResult& r) {
  ClearHistory h(all.gt_index.size());
  for (const Frame& f : all.frames) count_clear(f, clear_matches(f, h, matcher), h, r);
}

// HOTA's global alignment: per compact id its scans, per (gt, track) pair the sum of its
// similarity over the union of the two rows' similarities.
struct Alignment {
  explicit Alignment(std::size_t ngt, std::size_t ntrk_in)
      : ntrk(ntrk_in), gt_count(ngt, 0), trk_count(ntrk_in, 0) {}
  [[nodiscard]] std::uint64_t key(std::uint64_t g, std::uint64_t t) const { return g * ntrk + t; }
  std::size_t ntrk;
  std::vector<double> gt_count, trk_count;
  std::unordered_map<std::uint64_t, double> potential;  // key gt * ntrk + trk
};

Alignment alignment_of(const Frames& all) {
  Alignment a(all.gt_index.size(), all.trk_index.size());
  for (const Frame& f : all.frames) {
    const std::size_t ng = f.gt.size(), nt = f.trk.size();
    for (const auto g : f.gt) ++a.gt_count[g];
    for (const auto t : f.trk) ++a.trk_count[t];
    std::vector<double> row(ng, 0), col(nt, 0);
    for (std::size_t j = 0; j < ng; ++j) {
      for (std::size_t i = 0; i < nt; ++i) {
        row[j] += f.sim[j * nt + i];
        col[i] += f.sim[j * nt + i];
      }
    }
    for (std::size_t j = 0; j < ng; ++j) {
      for (std::size_t i = 0; i < nt; ++i) {
        const double s = f.sim[j * nt + i];
        const double denom = row[j] + col[i] - s;
        if (s > 0 && denom > kEps) a.potential[a.key(f.gt[j], f.trk[i])] += s / denom;
      }
    }
  }
  return a;
}

// A true positive of HOTA at one alpha, for AssA.
struct Event {
  int alpha;
  std::uint32_t g, t;
  std::string_view cls;
  int band;
};

// HOTA's true positives, per pair and alpha, and their events.
struct HotaMatches {
  std::vector<Event> events;
  std::unordered_map<std::uint64_t, std::array<double, kHotaAlphas>> count;
};

// One scan's assignment maximising alignment x similarity.
std::vector<int> hota_matches(const Frame& f, const Alignment& a, Matcher& matcher) {
  const std::size_t ng = f.gt.size(), nt = f.trk.size();
  std::vector<double> score(ng * nt);
  std::vector<bool> allowed(ng * nt);
  for (std::size_t j = 0; j < ng; ++j) {
    for (std::size_t i = 0; i < nt; ++i) {
      const std::uint64_t k = a.key(f.gt[j], f.trk[i]);
      const auto p = a.potential.find(k);
      const double pot = p == a.potential.end() ? 0.0 : p->second;
      const double align = pot / (a.gt_count[f.gt[j]] + a.trk_count[f.trk[i]] - pot);
      score[j * nt + i] = align * f.sim[j * nt + i];
      allowed[j * nt + i] = score[j * nt + i] > kEps;
    }
  }
  return matcher.maximise(score, allowed, ng, nt);
}

// One scan's HOTA counts at alpha index `al` from its matches m.
void count_hota(const Frame& f, const std::vector<int>& m, int al, const Alignment& a,
                HotaMatches& hm, EvalResult& r) {
  const std::size_t ng = f.gt.size(), nt = f.trk.size();
  std::vector<bool> trk_matched(nt, false);
  for (std::size_t j = 0; j < ng; ++j) {
    const bool hit =
        m[j] >= 0 && f.sim[j * nt + static_cast<std::size_t>(m[j])] >= alpha(al) - kEps;
    HotaCounts* counts[3] = {&r.hota, &r.hota_by_class[f.gt_class[j]],
                             &r.hota_by_band[f.gt_band[j]]};
    if (!hit) {
      for (HotaCounts* k : counts) ++k->fn[al];
      continue;
    }
    const auto i = static_cast<std::size_t>(m[j]);
    trk_matched[i] = true;
    for (HotaCounts* k : counts) {
      ++k->tp[al];
      k->loc_sum[al] += f.sim[j * nt + i];
    }
    ++hm.count[a.key(f.gt[j], f.trk[i])][al];
    hm.events.push_back({al, f.gt[j], f.trk[i], f.gt_class[j], f.gt_band[j]});
  }
  for (std::size_t i = 0; i < nt; ++i) {
    if (trk_matched[i]) continue;
    ++r.hota.fp[al];
    ++r.hota_by_band[f.trk_band[i]].fp[al];
    if (!f.trk_class[i].empty()) ++r.hota_by_class[f.trk_class[i]].fp[al];
  }
}

// HOTA (TrackEval's definition): global alignment scores first, then per-scan matching; AssA
// weighs each true positive by the association IoU of its (gt, track) pair.
void hota(const Frames& all, Matcher& matcher, EvalResult& r) {
  const Alignment a = alignment_of(all);
  HotaMatches hm;
  for (const Frame& f : all.frames) {
    const std::vector<int> m = hota_matches(f, a, matcher);
    for (int al = 0; al < kHotaAlphas; ++al) count_hota(f, m, al, a, hm, r);
  }
  for (const Event& e : hm.events) {
    const double mc = hm.count[a.key(e.g, e.t)][e.alpha];
    const double ass = mc / (a.gt_count[e.g] + a.trk_count[e.t] - mc);
    r.hota.ass_sum[e.alpha] += ass;
    r.hota_by_class[std::string(e.cls)].ass_sum[e.alpha] += ass;
    r.hota_by_band[e.band].ass_sum[e.alpha] += ass;
  }
}

}  // namespace

bool is_tracked_class(const EvalConfig& config, const std::string& cls) {
  return config.zero_distance_m.count(cls) != 0;
}

double ClearCounts::mota() const {
  return 1.0 - static_cast<double>(fn + fp + id_switches) /
                   static_cast<double>(std::max<std::uint64_t>(1, gt));
}
double ClearCounts::motp() const {
  return tp == 0 ? 0.0 : similarity_sum / static_cast<double>(tp);
}
double ClearCounts::motp_distance_m() const {
  return tp == 0 ? 0.0 : distance_sum_m / static_cast<double>(tp);
}
double ClearCounts::recall() const {
  return gt == 0 ? 0.0 : static_cast<double>(tp) / static_cast<double>(gt);
}

double HotaCounts::deta() const {
  double sum = 0;
  for (int a = 0; a < kHotaAlphas; ++a) sum += tp[a] / std::max(1.0, tp[a] + fn[a] + fp[a]);
  return sum / kHotaAlphas;
}
double HotaCounts::assa() const {
  double sum = 0;
  for (int a = 0; a < kHotaAlphas; ++a) sum += ass_sum[a] / std::max(1.0, tp[a]);
  return sum / kHotaAlphas;
}
double HotaCounts::hota() const {
  double sum = 0;
  for (int a = 0; a < kHotaAlphas; ++a) {
    const double det = tp[a] / std::max(1.0, tp[a] + fn[a] + fp[a]);
    const double ass = ass_sum[a] / std::max(1.0, tp[a]);
    sum += std::sqrt(det * ass);
  }
  return sum / kHotaAlphas;
}
double HotaCounts::detre() const {
  double sum = 0;
  for (int a = 0; a < kHotaAlphas; ++a) sum += tp[a] / std::max(1.0, tp[a] + fn[a]);
  return sum / kHotaAlphas;
}
double HotaCounts::loca() const {
  double sum = 0;
  for (int a = 0; a < kHotaAlphas; ++a) sum += loc_sum[a] / std::max(1.0, tp[a]);
  return sum / kHotaAlphas;
}
double SegCounts::over_rate() const {
  return objects == 0 ? 0.0 : static_cast<double>(over) / static_cast<double>(objects);
}
double SegCounts::under_rate() const {
  return objects == 0 ? 0.0 : static_cast<double>(under) / static_cast<double>(objects);
}

EvalResult evaluate(const std::vector<TruthScanRecord>& truth_in,
                    const std::vector<TracksScan>& tracks_in, const EvalConfig& c) {
  EvalResult r;
  r.fp_by_class = c.classified_outputs_only;
  r.truth_scans = truth_in.size();
  r.output_scans = tracks_in.size();
  const std::vector<ScanPair> pairs = pair_scans(truth_in, tracks_in, c);
  r.paired_scans = pairs.size();
  Matcher matcher;
  const Frames frames = frames_of(pairs, c, matcher, r);
  clear_mot(frames, matcher, r);
  hota(frames, matcher, r);
  // A class may have its false positives in one count and none in the other: both hold it.
  for (const auto& [cls, k] : r.clear_by_class) (void)r.hota_by_class[cls];
  for (const auto& [cls, k] : r.hota_by_class) (void)r.clear_by_class[cls];
  return r;
}

}  // namespace stac::evaluation
