// Group induction as a resumable workflow (stac induct, stac label) (thesis ch. 2;
// docs/learning.md). A state folder keeps the user's labels, the background set B0, the buffer of
// unlabeled groups and the model; each unlabeled dataset given is one chunk of the stream and one
// round (induction phase, then warm-started training); after a round the tracks the model is least
// sure of (and its confident positives the user has never seen) are written as questions, answered
// by the user
// (`stac label`, or labels.jsonl by hand) or, with --oracle, from the datasets' truth.
#include "perception/induction/session.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <numeric>
#include <optional>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "formats/dataset_file.hpp"
#include "formats/durable_file.hpp"
#include "formats/folder_lock.hpp"
#include "formats/induction_state.hpp"
#include "formats/model_file.hpp"
#include "perception/classification/holistic.hpp"
#include "perception/descriptors/descriptors.hpp"
#include "perception/learning/induction.hpp"
#include "pictures/chart.hpp"
#include "rt/formatted.hpp"

namespace stac::induction {

using namespace stac::formats;
namespace {

using rt::formatted;

using classification::ClassIndex;
using classification::kBackground;
using classification::LogOdds;
namespace fs = std::filesystem;

constexpr std::size_t kSegDims = descriptors::kDimensions;
constexpr std::size_t kHolDims = classification::kHolisticDimensions;

learning::TrackExample example_of(const DatasetTrack& t, ClassIndex label) {
  learning::TrackExample e = track_example(DatasetTrack(t));
  e.label = label;
  return e;
}

// The model's track log odds (ADBF) over a track's segments and its last holistic descriptor.
LogOdds track_log_odds(const classification::TrackClassifierModel& model, const DatasetTrack& t) {
  classification::TrackEvidence evidence;
  LogOdds h{}, out{};
  for (std::size_t i = 0; i + kSegDims <= t.segment_rows.size(); i += kSegDims)
    (void)add_segment(model, std::span(t.segment_rows).subspan(i, kSegDims), evidence, h);
  (void)classification::track_log_odds(model, evidence, std::span(t.holistic_rows).last(kHolDims),
                                       out);
  return out;
}

class Inductor {
 public:
  Inductor(const SessionOptions& o, const SessionOutput& out) : o_(o), out_(out), dir_(o.state) {}
  rt::Status run();

 private:
  rt::Status open_state();
  rt::Result<const Dataset*> dataset(const std::string& path);
  rt::Result<std::uint32_t> source_index(const std::string& path, SourceRole role);
  rt::Status read_background();
  rt::Status seed_labels();
  rt::Status apply_answers();
  rt::Status round(std::uint32_t chunk, std::vector<learning::Group> groups);
  rt::Status ask(const std::vector<std::uint32_t>& chunks);
  rt::Status save(const std::string& what);
  rt::Status chart();
  rt::Status export_labels();
  [[nodiscard]] std::vector<learning::TrackExample> label_examples() const;
  [[nodiscard]] double accuracy(const classification::TrackClassifierModel& model);
  [[nodiscard]] bool seen(std::uint32_t source, std::uint64_t track) const {
    return seen_.count({source, track}) != 0;
  }
  [[nodiscard]] learning::TrainingPhaseConfig phase() const;
  [[nodiscard]] bool kept(std::size_t k) const { return ((s_.kept_classes >> k) & 1u) != 0; }
  // A fitted filter into `m`, but for the kept classes, which keep theirs.
  void take_filter(classification::TrackClassifierModel& m,
                   const classification::AdbfParams& fitted) const {
    for (std::size_t k = 0; k < s_.classes.size(); ++k) {
      if (kept(k)) continue;
      m.adbf.alpha[k] = fitted.alpha[k];
      m.adbf.beta[k] = fitted.beta[k];
      m.adbf.gamma[k] = fitted.gamma[k];
    }
  }

  const SessionOptions& o_;
  const SessionOutput& out_;
  fs::path dir_;
  InductionState s_;
  std::map<std::string, Dataset> datasets_;
  std::vector<learning::TrackExample> b0_;
  std::set<std::pair<std::uint32_t, std::uint64_t>> seen_;
  std::vector<std::string> pending_history_;
  bool creating_ = false;
  std::optional<FolderLock> lock_;  // one stac induct at a time on a state folder
};

learning::TrainingPhaseConfig Inductor::phase() const {
  learning::TrainingPhaseConfig c;
  c.warm_rounds = o_.warm_rounds;
  c.reset_rounds = o_.reset_rounds;
  c.segment.seed = o_.seed + 2ull * s_.rounds;
  c.holistic.seed = o_.seed + 2ull * s_.rounds + 1;
  c.kept = s_.kept_classes;
  return c;
}

rt::Result<const Dataset*> Inductor::dataset(const std::string& path) {
  if (auto it = datasets_.find(path); it != datasets_.end()) return &it->second;
  auto d = read_dataset(path);
  if (!d) return rt::make_error(d.error().message);
  if (auto b = bind_source_dataset(s_.sources, path, d->checksum); !b)
    return rt::make_error(b.error().message);
  // Labels map by name: every class of the state must be one of the dataset's; its other
  // classes are background here (1-vs-all: not any taught class). Unlabeled data has no classes.
  if (auto m = map_classes(*d, s_.classes, path + " (for the state's classes)"); !m)
    return rt::make_error(m.error().message);
  return &datasets_.emplace(path, std::move(d).value()).first->second;
}

rt::Result<std::uint32_t> Inductor::source_index(const std::string& path, SourceRole role) {
  for (std::uint32_t i = 0; i < s_.sources.size(); ++i)
    if (s_.sources[i].path == path) {
      if (s_.sources[i].role != role && role == SourceRole::kBackground)
        return rt::make_error(path +
                              ": already read as labelled or unlabeled data; B0 must hold only "
                              "drives without the taught classes");
      if (s_.sources[i].role != role && s_.sources[i].role == SourceRole::kBackground)
        return rt::make_error(path + ": this state read it as B0 (--background: drives without " +
                              "the taught classes, every track background); it cannot be " +
                              (role == SourceRole::kLabels ? "--labels" : "--unlabeled") +
                              " data too");
      return i;
    }
  s_.sources.push_back({path, role});
  if (auto it = datasets_.find(path); it != datasets_.end())  // read before it became a source
    if (auto b = bind_source_dataset(s_.sources, path, it->second.checksum); !b)
      return rt::make_error(b.error().message);
  return static_cast<std::uint32_t>(s_.sources.size() - 1);
}

rt::Status Inductor::open_state() {
  std::error_code ec;
  if (fs::is_directory(dir_, ec)) {  // before reading anything of it: one writer at a time
    auto lock = FolderLock::acquire(dir_, "the induction state");
    if (!lock) return rt::make_error(lock.error().message);
    lock_.emplace(std::move(lock).value());
  }
  const bool exists = fs::exists(dir_ / "state.bin", ec);
  if (exists) {
    auto s = read_induction_state(dir_);
    if (!s) return rt::make_error(s.error().message);
    // The command that created the state may be given again (a rerun after a kill): its
    // settings must be the state's; other ones are refused.
    std::vector<std::string> asked;
    std::stringstream list(o_.classes);
    for (std::string name; std::getline(list, name, ',');) asked.push_back(name);
    // Each setting given that is not the state's, with the state's value and the one given.
    std::string differ;
    const auto note = [&differ](const std::string& what) {
      differ += (differ.empty() ? "" : "; ") + what;
    };
    if (!o_.classes.empty() && asked != s->classes)
      note("--classes " + o_.classes + " (the state's: " + classification::joined(s->classes) +
           ")");
    if (!o_.model.empty()) note("--model " + o_.model + " (a model starts a state only)");
    if (!o_.add_classes.empty())
      note("--add-classes " + o_.add_classes + " (added when a state starts only)");
    const auto num = [](double v) {
      std::ostringstream t;
      t << v;
      return t.str();
    };
    if (o_.dual_given && o_.dual != s->induction.dual)
      note(std::string("--dual ") + (o_.dual ? "on" : "off") +
           " (the state's: " + (s->induction.dual ? "on" : "off") + ")");
    if (o_.eps_given && o_.eps != s->induction.eps_max)
      note("--eps " + num(o_.eps) + " (the state's: " + num(s->induction.eps_max) + ")");
    if (o_.group_given && o_.group_size != s->induction.max_group_size)
      note("--group-size " + std::to_string(o_.group_size) +
           " (the state's: " + std::to_string(s->induction.max_group_size) + ")");
    if (o_.buffer_given && o_.buffer != s->induction.buffer_groups)
      note("--buffer " + std::to_string(o_.buffer) +
           " (the state's: " + std::to_string(s->induction.buffer_groups) + ")");
    if (!differ.empty())
      return rt::make_error(dir_.string() + ": the state exists with other settings: " + differ +
                            ". --classes, --model, --add-classes, --dual, --eps, --group-size and "
                            "--buffer are set when it is created (leave them out to go on, or "
                            "start a new folder to change them)");
    s_ = std::move(s).value();
  } else {
    if (fs::exists(dir_, ec) && !fs::is_directory(dir_, ec))
      return rt::make_error(dir_.string() + ": exists and is not a folder");
    if (o_.classes.empty() == o_.model.empty())
      return rt::make_error(dir_.string() +
                            ": no state here yet; start one with --classes NAME,NAME,... or "
                            "--model FILE (one of them)");
    if (!o_.add_classes.empty() && o_.model.empty())
      return rt::make_error("--add-classes " + o_.add_classes +
                            ": give the model they are added to with --model FILE");
    if (!o_.model.empty()) {
      auto m = read_model_file(o_.model);
      if (!m) return rt::make_error(m.error().message);
      s_.model = std::move(m).value();
      s_.has_model = true;
      s_.reset_pending = false;  // warm start from the given model
      if (!o_.add_classes.empty()) {
        // The model's classes are kept as they are; the added ones start from zero (the first
        // round resets them only, with priors from the data, and boosts them from there).
        classification::ClassNames added;
        std::stringstream list(o_.add_classes);
        for (std::string name; std::getline(list, name, ',');) added.push_back(name);
        auto wider = learning::with_added_classes(s_.model, added);
        if (!wider)
          return rt::make_error("--add-classes " + o_.add_classes + ": " + wider.error().message);
        s_.kept_classes = (1u << s_.model.classes.size()) - 1u;
        s_.model = std::move(wider).value();
        s_.reset_pending = true;
      }
      s_.classes = s_.model.classes;
    } else {
      std::stringstream list(o_.classes);
      for (std::string name; std::getline(list, name, ',');) s_.classes.push_back(name);
      if (const std::string bad = classification::check_class_names(s_.classes); !bad.empty())
        return rt::make_error("--classes " + o_.classes + ": " + bad);
    }
    if (!std::isfinite(o_.eps)) return rt::make_error("--eps must be a number in [0, 100]");
    s_.induction.dual = o_.dual;
    s_.induction.eps_max = o_.eps;
    s_.induction.max_group_size = o_.group_size;
    s_.induction.buffer_groups = o_.buffer;
    if (const std::string bad = learning::validate(s_.induction); !bad.empty())
      return rt::make_error(bad);
    creating_ = true;  // on disk once every input has been read (run())
  }
  for (const auto& p : s_.seen) seen_.insert(p);
  return {};
}

rt::Status Inductor::read_background() {
  for (const std::string& path : o_.background)
    if (auto i = source_index(path, SourceRole::kBackground); !i)
      return rt::make_error(i.error().message);
  for (const InductionSource& src : s_.sources) {
    if (src.role != SourceRole::kBackground) continue;
    auto d = dataset(src.path);
    if (!d) return rt::make_error(d.error().message);
    for (const DatasetTrack& t : (*d)->tracks) b0_.push_back(example_of(t, kBackground));
  }
  return {};
}

// --labels: up to --labels-per-class tracks of each class (and of background), drawn with
// --seed, appended to labels.jsonl as answers.
rt::Status Inductor::seed_labels() {
  std::mt19937_64 rng(o_.seed);
  for (const std::string& path : o_.labels) {
    auto i = source_index(path, SourceRole::kLabels);
    if (!i) return rt::make_error(i.error().message);
    auto d = dataset(path);
    if (!d) return rt::make_error(d.error().message);
    std::vector<std::size_t> order((*d)->tracks.size());
    std::iota(order.begin(), order.end(), std::size_t{0});
    std::shuffle(order.begin(), order.end(), rng);
    std::vector<std::size_t> taken(s_.classes.size() + 1, 0);  // with the earlier runs' labels
    for (const LabelledTrack& t : s_.labels)
      if (t.source == *i) ++taken[t.label == kBackground ? s_.classes.size() : t.label];
    for (const std::size_t k : order) {
      const DatasetTrack& t = (*d)->tracks[k];
      if (!consistent(t) || seen(*i, k) || (t.label != kBackground && kept(t.label))) continue;
      std::size_t& n = taken[t.label == kBackground ? s_.classes.size() : t.label];
      if (o_.labels_per_class != 0 && n >= o_.labels_per_class) continue;
      ++n;
      const nlohmann::json answer = {{"source", path},
                                     {"track", k},
                                     {"label", classification::class_name(s_.classes, t.label)}};
      if (auto a = append_line_durably(dir_ / "labels.jsonl", answer.dump()); !a) return a;
    }
  }
  return {};
}

std::vector<learning::TrackExample> Inductor::label_examples() const {
  std::vector<learning::TrackExample> out;
  out.reserve(s_.labels.size());
  for (const LabelledTrack& t : s_.labels) out.push_back({t.label, t.segments, t.holistic});
  return out;
}

// The answers of labels.jsonl not taken yet; new labels trigger retrospection (thesis 2.3.2).
rt::Status Inductor::apply_answers() {
  const fs::path file = dir_ / "labels.jsonl";
  std::ifstream in(file);
  if (!in) return {};  // no answer yet
  std::vector<learning::TrackExample> fresh;
  std::uint64_t line_no = 0;
  std::size_t skipped = 0;
  // Every line is read each time; an answer is known by its dataset and track (seen_), so a
  // line deleted or moved by hand moves no other answer (issue 47). A torn last line was cut or
  // completed before (run(): complete_or_cut_tail), so every line here was written whole.
  for (std::string line; std::getline(in, line);) {
    ++line_no;
    const auto bad = [&](const std::string& what) {
      return rt::make_error(file.string() + ":" + std::to_string(line_no) + ": " + what +
                            "; fix or delete that line (each line: {\"source\": DATASET, "
                            "\"track\": INDEX, \"label\": CLASS | \"background\" | \"skip\"})");
    };
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    if (!is_answer_line(line)) return bad("not an answer");
    const nlohmann::json j = nlohmann::json::parse(line);
    const std::string path = j["source"].get<std::string>();
    const auto track = j["track"].get<std::uint64_t>();
    const std::string label = j["label"].get<std::string>();
    std::uint32_t source = 0;
    bool known = false;
    for (std::uint32_t i = 0; i < s_.sources.size(); ++i)
      if (s_.sources[i].path == path) source = i, known = true;
    if (!known || s_.sources[source].role == SourceRole::kBackground)
      return bad("source " + path + " is not a dataset this state read as labels or unlabeled");
    auto d = dataset(path);
    if (!d) return bad(d.error().message);
    if (track >= (*d)->tracks.size())
      return bad("track " + std::to_string(track) + " is past the " +
                 std::to_string((*d)->tracks.size()) + " tracks of " + path);
    ClassIndex cls = kBackground;
    if (label != "skip" && label != "background") {
      const auto it = std::find(s_.classes.begin(), s_.classes.end(), label);
      if (it == s_.classes.end())
        return bad("label " + label + " is none of " + classification::joined(s_.classes) +
                   ", background, skip");
      cls = static_cast<ClassIndex>(it - s_.classes.begin());
    }
    if (seen(source, track)) continue;  // answered before: the first answer holds
    s_.answers_applied = line_no;
    seen_.insert({source, track});
    s_.seen.emplace_back(source, track);
    if (label == "skip") {
      ++skipped;
      continue;
    }
    const DatasetTrack& t = (*d)->tracks[track];
    const learning::TrackExample e = example_of(t, cls);
    s_.labels.push_back({source, track, cls, e.segments, e.holistic});
    fresh.push_back(e);
    // A labelled track's groups leave the buffer: it is supervised now.
    std::erase_if(s_.buffer,
                  [&](const learning::Group& g) { return g.source == source && g.track == track; });
  }
  if (!fresh.empty() && s_.has_model) {
    const LogOdds eps = learning::retrospection_noise(
        s_.model.segment, fresh, kSegDims, s_.induction.eps_max, s_.induction.max_group_size);
    const auto summary = learning::induction_phase(s_.model.segment, s_.buffer, s_.induction, eps);
    std::size_t de = 0;
    for (const auto& c : summary.changes) de += c.to == learning::kUninducted ? 1 : 0;
    nlohmann::json e = nlohmann::json::array();
    for (std::size_t k = 0; k < s_.classes.size(); ++k) e.push_back(eps[k]);
    pending_history_.push_back(nlohmann::json{
        {"event", "retrospection"},
        {"after_round", s_.rounds},
        {"new_labels", fresh.size()},
        {"skipped", skipped},
        {"eps", e},
        {"de_inducted", de}}.dump());
    out_.line(formatted("retrospection: %zu new labels, %zu groups de-inducted, H reset",
                        fresh.size(), de));
    s_.reset_pending = true;
  }
  return {};
}

double Inductor::accuracy(const classification::TrackClassifierModel& model) {
  std::size_t right = 0, total = 0;
  for (const std::string& path : o_.eval) {
    auto d = dataset(path);
    if (!d) continue;  // checked before the rounds
    for (const DatasetTrack& t : (*d)->tracks) {
      if (!consistent(t)) continue;
      ++total;
      right += classification::predict(track_log_odds(model, t), model.classes.size()) == t.label
                   ? 1
                   : 0;
    }
  }
  return total == 0 ? 0.0 : static_cast<double>(right) / static_cast<double>(total);
}

rt::Status Inductor::save(const std::string& what) {
  if (auto w = write_induction_state(dir_, s_); !w)
    return rt::make_error(w.error().message + " (" + what + ")");
  for (const std::string& line : pending_history_)
    if (auto a = append_line_durably(dir_ / "history.jsonl", line); !a) return a;
  pending_history_.clear();
  if (s_.has_model) {
    char name[32];
    std::snprintf(name, sizeof name, "round-%04u.stacmodel", s_.rounds);
    std::error_code ec;
    fs::create_directories(dir_ / "models", ec);
    if (auto m = write_model_file(dir_ / "models" / name, s_.model); !m) return m;
    if (auto m = write_model_file(dir_ / "model.stacmodel", s_.model); !m) return m;
  }
  return {};
}

rt::Status Inductor::round(std::uint32_t chunk, std::vector<learning::Group> groups) {
  const auto started = std::chrono::steady_clock::now();
  const std::size_t classes = s_.classes.size();
  // Every third user label and B0 track is kept out of boosting for the filter's fit, as
  // `stac train` holds tracks out (fitted on tracks boosting has seen, the weights trust the
  // overconfident holistic classifier: held-out accuracy fell from 0.93 to 0.79 in a round).
  std::vector<learning::TrackExample> labels, filter_tracks, background;
  {
    std::vector<learning::TrackExample> all = label_examples();
    for (std::size_t i = 0; i < all.size(); ++i)
      (i % 3 == 2 ? filter_tracks : labels).push_back(std::move(all[i]));
    for (std::size_t i = 0; i < b0_.size(); ++i)
      (i % 3 == 2 ? filter_tracks : background).push_back(b0_[i]);
  }
  if (!s_.has_model) {
    const auto range =
        learning::round_data(labels, background, groups, classes, kSegDims, kHolDims);
    const auto data = learning::round_data(labels, background, {}, classes, kSegDims, kHolDims);
    if (data.segments.size() == 0)
      return rt::make_error(
          "no labelled track and no background yet: give --labels DATASET (a few tracks per "
          "class) and --background DATASET (drives without the taught classes)");
    auto m =
        learning::initial_model(s_.classes, range, data, classification::build_layouts(), phase());
    if (!m) return rt::make_error(m.error().message);
    s_.model = std::move(m).value();
    s_.has_model = true;
    s_.reset_pending = true;
  }
  const bool reset = s_.reset_pending;
  if (reset) {
    auto m = learning::training_phase(
        s_.model, learning::round_data(labels, background, s_.buffer, classes, kSegDims, kHolDims),
        true, phase());
    if (!m) return rt::make_error(m.error().message);
    s_.model = std::move(m).value();
    s_.reset_pending = false;
  }
  const std::size_t before = s_.buffer.size();
  for (learning::Group& g : groups) s_.buffer.push_back(std::move(g));
  const auto summary = learning::induction_phase(s_.model.segment, s_.buffer, s_.induction,
                                                 learning::uniform_noise(s_.induction.eps_max));
  std::size_t newly = 0, de = 0;
  for (const auto& c : summary.changes) {
    if (c.to == learning::kUninducted)
      ++de;
    else if (c.from == learning::kUninducted)
      ++newly;
  }
  const std::size_t offered = s_.buffer.size();
  learning::keep_most_useful(s_.buffer, s_.induction.buffer_groups);
  auto next = learning::training_phase(
      s_.model, learning::round_data(labels, background, s_.buffer, classes, kSegDims, kHolDims),
      false, phase());
  if (!next) return rt::make_error(next.error().message);
  s_.model = std::move(next).value();
  if (chunk < s_.sources.size()) s_.sources[chunk].stage = ChunkStage::kTrained;
  if (!filter_tracks.empty()) {
    auto adbf = learning::fit_filter(s_.model, filter_tracks, kSegDims, learning::LogisticConfig{});
    if (!adbf) return rt::make_error("the filter's fit: " + adbf.error().message);
    take_filter(s_.model, *adbf);
  }
  ++s_.rounds;

  nlohmann::json user = nlohmann::json::object(), inducted = nlohmann::json::object();
  std::vector<std::size_t> per(classes + 1, 0), in_buffer(classes + 1, 0);
  for (const LabelledTrack& t : s_.labels) ++per[t.label == kBackground ? classes : t.label];
  for (const learning::Group& g : s_.buffer)
    if (g.label != learning::kUninducted) ++in_buffer[g.label == kBackground ? classes : g.label];
  for (std::size_t c = 0; c <= classes; ++c) {
    const char* name = c < classes ? s_.classes[c].c_str() : "background";
    user[name] = per[c];
    inducted[name] = in_buffer[c];
  }
  nlohmann::json line = {
      {"event", "round"},
      {"round", s_.rounds},
      {"chunk", chunk < s_.sources.size() ? s_.sources[chunk].path : ""},
      {"user_labels", user},
      {"background_tracks", b0_.size()},
      {"groups_offered", offered - before},
      {"buffer", s_.buffer.size()},
      {"dropped_from_buffer", offered - s_.buffer.size()},
      {"inducted", inducted},
      {"newly_inducted", newly},
      {"de_inducted", de},
      {"reset", reset},
      {"seconds",
       std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count()}};
  if (o_.oracle) {
    // The truth the oracle answers from: how many inducted groups carry their track's class.
    std::size_t right = 0, total = 0;
    for (const learning::Group& g : s_.buffer) {
      if (g.label == learning::kUninducted || s_.sources[g.source].role != SourceRole::kUnlabeled)
        continue;
      auto d = dataset(s_.sources[g.source].path);
      if (!d || g.track >= (*d)->tracks.size()) continue;
      ++total;
      right += (*d)->tracks[g.track].label == g.label ? 1 : 0;
    }
    line["inducted_right"] = right;
    line["inducted_checked"] = total;
  }
  std::string acc;
  if (!o_.eval.empty()) {
    const double a = accuracy(s_.model);
    line["accuracy"] = a;
    char text[96];
    std::snprintf(text, sizeof text, ", held-out accuracy %.3f", a);
    acc = text;
    if (o_.baseline) {
      // The thesis's comparison: the same user labels and B0 without induction, trained from
      // zero with the rounds a reset gets, its filter fitted the same way.
      auto alone = learning::training_phase(
          s_.model, learning::round_data(labels, background, {}, classes, kSegDims, kHolDims), true,
          phase());
      if (!alone) return rt::make_error("--baseline: " + alone.error().message);
      if (!filter_tracks.empty()) {
        auto adbf =
            learning::fit_filter(*alone, filter_tracks, kSegDims, learning::LogisticConfig{});
        if (!adbf) return rt::make_error("--baseline: the filter's fit: " + adbf.error().message);
        take_filter(*alone, *adbf);
      }
      const double b = accuracy(*alone);
      line["accuracy_labels_only"] = b;
      std::snprintf(text, sizeof text, ", held-out accuracy %.3f (%.3f without induction)", a, b);
      acc = text;
    }
  }
  pending_history_.push_back(line.dump());
  std::size_t user_total = 0, inducted_total = 0;
  for (std::size_t c = 0; c <= classes; ++c) user_total += per[c], inducted_total += in_buffer[c];
  out_.line(
      formatted("round %u: %zu user labels, %zu groups in the buffer (%zu inducted, +%zu -%zu)%s",
                s_.rounds, user_total, s_.buffer.size(), inducted_total, newly, de, acc.c_str()));
  return save("round " + std::to_string(s_.rounds));
}

// Questions about the tracks of `chunks` (one chunk after its round; every unlabeled chunk with
// --requery): written to queries.jsonl; with --oracle answered from the datasets' truth labels
// (an inconsistent track is skipped, as a person would).
rt::Status Inductor::ask(const std::vector<std::uint32_t>& chunks) {
  struct Asked {
    std::uint32_t chunk;
    std::size_t track;
  };
  std::vector<learning::QueryCandidate> candidates;
  std::vector<Asked> where;
  for (const std::uint32_t chunk : chunks) {
    auto d = dataset(s_.sources[chunk].path);
    if (!d) return rt::make_error(d.error().message);
    for (std::size_t k = 0; k < (*d)->tracks.size(); ++k) {
      candidates.push_back({track_log_odds(s_.model, (*d)->tracks[k]), seen(chunk, k)});
      where.push_back({chunk, k});
    }
  }
  const auto chosen = learning::choose_queries(
      candidates, s_.classes.size(), {o_.ask, o_.ask_confident.value_or(o_.ask)}, s_.kept_classes);
  std::string text;
  for (const std::size_t k : chosen) {
    nlohmann::json lo = nlohmann::json::object();
    for (std::size_t c = 0; c < s_.classes.size(); ++c)
      lo[s_.classes[c]] = candidates[k].log_odds[c];
    text +=
        nlohmann::json{{"source", s_.sources[where[k].chunk].path},
                       {"track", where[k].track},
                       {"predicted", classification::class_name(
                                         s_.classes, classification::predict(candidates[k].log_odds,
                                                                             s_.classes.size()))},
                       {"log_odds", lo},
                       {"round", s_.rounds}}
            .dump() +
        "\n";
  }
  if (auto w = write_file_durably(
          dir_ / "queries.jsonl",
          std::span(reinterpret_cast<const std::uint8_t*>(text.data()), text.size()));
      !w)
    return w;
  for (const std::uint32_t chunk : chunks)
    if (s_.sources[chunk].stage == ChunkStage::kTrained)
      s_.sources[chunk].stage = ChunkStage::kAsked;
  if (!o_.oracle) return save("questions");
  for (const std::size_t k : chosen) {
    const DatasetTrack& t = (*dataset(s_.sources[where[k].chunk].path))->tracks[where[k].track];
    const char* label = consistent(t) ? classification::class_name(s_.classes, t.label) : "skip";
    const nlohmann::json answer = {
        {"source", s_.sources[where[k].chunk].path}, {"track", where[k].track}, {"label", label}};
    if (auto a = append_line_durably(dir_ / "labels.jsonl", answer.dump()); !a) return a;
  }
  if (auto a = apply_answers(); !a) return a;
  return save("answers");
}

// DIR/learning.png: held-out accuracy after each round against the user labels so far (the
// thesis's Fig. 2.6), with --reference lines.
rt::Status Inductor::chart() {
  std::ifstream in(dir_ / "history.jsonl");
  pictures::ChartSeries curve{"group induction", {}, {}},
      alone{"same labels, no induction", {}, {}};
  for (std::string line; std::getline(in, line);) {
    const nlohmann::json j = nlohmann::json::parse(line, nullptr, false);
    if (j.is_discarded() || !j.is_object() || j.value("event", "") != "round" ||
        !j.contains("accuracy") || !j.contains("user_labels"))
      continue;
    double labels = 0;
    for (const auto& [name, n] : j["user_labels"].items()) labels += n.get<double>();
    curve.x.push_back(labels);
    curve.y.push_back(j["accuracy"].get<double>());
    if (j.contains("accuracy_labels_only")) {
      alone.x.push_back(labels);
      alone.y.push_back(j["accuracy_labels_only"].get<double>());
    }
  }
  if (curve.x.empty()) return {};
  pictures::Chart c;
  c.title = "held-out track accuracy (" + classification::joined(s_.classes) + ", background)";
  c.x_label = "user labels";
  c.y_label = "accuracy";
  c.series.push_back(curve);
  if (!alone.x.empty()) c.series.push_back(alone);
  for (const std::string& r : o_.references) {
    const auto eq = r.rfind('=');
    char* end = nullptr;
    const double v = eq == std::string::npos ? NAN : std::strtod(r.c_str() + eq + 1, &end);
    if (eq == 0 || !std::isfinite(v) || end == nullptr || *end != '\0')
      return rt::make_error("--reference " + r + ": not NAME=ACCURACY");
    c.series.push_back({r.substr(0, eq), {curve.x.front(), curve.x.back()}, {v, v}});
  }
  double lowest = 1.0;
  for (const pictures::ChartSeries& s : c.series)
    for (const double y : s.y) lowest = std::min(lowest, y);
  c.y_min = std::max(0.0, std::floor((lowest - 0.02) * 10.0) / 10.0);
  return pictures::save_chart(c, dir_ / "learning.png");
}

// --export: the user's labels (the tracks as their datasets hold them, with the user's label)
// and B0 as one dataset, for `stac train` on the same labels without induction.
rt::Status Inductor::export_labels() {
  Dataset out;
  out.classes = s_.classes;
  for (const InductionSource& src : s_.sources) {
    if (src.role != SourceRole::kBackground) continue;
    auto d = dataset(src.path);
    if (!d) return rt::make_error(d.error().message);
    Dataset copy = **d;
    for (DatasetTrack& t : copy.tracks) t.label = kBackground;
    if (auto a = append_dataset(out, std::move(copy), src.path); !a) return a;
  }
  for (const LabelledTrack& t : s_.labels) {
    auto d = dataset(s_.sources[t.source].path);
    if (!d) return rt::make_error(d.error().message);
    DatasetTrack copy = (*d)->tracks[t.track];
    copy.label = t.label;
    copy.off_label_segments = 0;  // the user's word
    copy.source = static_cast<std::uint32_t>(out.sources.size());
    out.sources.push_back((*d)->sources[(*d)->tracks[t.track].source]);
    out.tracks.push_back(std::move(copy));
  }
  if (auto w = write_dataset(o_.export_dir, out); !w) return w;
  out_.line(formatted("exported %zu user labels and %zu B0 tracks to %s", s_.labels.size(),
                      out.tracks.size() - s_.labels.size(), o_.export_dir.c_str()));
  return {};
}

rt::Status Inductor::run() {
  if (auto r = open_state(); !r) return rt::make_error(r.error().message);
  const auto labelled = [this](const std::string& path, const char* what) -> rt::Status {
    auto d = dataset(path);
    if (!d) return rt::make_error(d.error().message);
    if (!(*d)->labelled)
      return rt::make_error(path + ": has no labels (made by `stac dataset` without --truth); " +
                            what + " needs labelled tracks");
    return {};
  };
  for (const std::string& path : o_.eval)
    if (auto r = labelled(path, "--eval"); !r) return rt::make_error(r.error().message);
  if (auto r = read_background(); !r) return rt::make_error(r.error().message);
  for (const std::string& path : o_.labels) {
    if (auto r = labelled(path, "--labels"); !r) return rt::make_error(r.error().message);
    // Known before a killed run's answers are read: they may come from it.
    if (auto i = source_index(path, SourceRole::kLabels); !i)
      return rt::make_error(i.error().message);
  }
  std::vector<std::uint32_t> chunks;
  for (const std::string& path : o_.unlabeled) {
    auto i = source_index(path, SourceRole::kUnlabeled);
    if (!i) return rt::make_error(i.error().message);
    if (auto d = dataset(path); !d) return rt::make_error(d.error().message);
    if (o_.oracle)
      if (auto r = labelled(path, "--oracle"); !r) return rt::make_error(r.error().message);
    chunks.push_back(*i);
  }
  if (creating_) {  // every input read: the new state goes to disk
    std::error_code ec;
    fs::create_directories(dir_ / "models", ec);
    if (ec)
      return rt::make_error(dir_.string() + ": cannot create the state folder (" + ec.message() +
                            ")");
    if (!lock_) {
      auto lock = FolderLock::acquire(dir_, "the induction state");
      if (!lock) return rt::make_error(lock.error().message);
      lock_.emplace(std::move(lock).value());
      if (fs::exists(dir_ / "state.bin", ec))
        return rt::make_error(dir_.string() +
                              ": another stac induct created a state here meanwhile; run "
                              "this again to continue it");
    }
  }
  // A kill during an append leaves a torn last line; a person's last answer may lack its newline.
  if (auto r = complete_or_cut_tail(dir_ / "labels.jsonl", is_answer_line, is_json_line); !r)
    return rt::make_error(r.error().message);
  else if (*r)
    out_.warning((dir_ / "labels.jsonl").string() +
                 ": its last line was torn (not a whole answer), cut off");
  if (auto r = cut_torn_tail(dir_ / "history.jsonl"); !r) return rt::make_error(r.error().message);
  if (auto r = apply_answers(); !r)
    return rt::make_error(r.error().message);  // a killed run's answers
  if (auto r = seed_labels(); !r) return rt::make_error(r.error().message);
  if (auto r = apply_answers(); !r) return rt::make_error(r.error().message);
  if (auto r = save("labels"); !r) return rt::make_error(r.error().message);
  const std::size_t total = chunks.size() + o_.rounds;
  std::size_t done = 0;
  const auto progress = [&] { out_.progress(++done, total); };
  for (const std::uint32_t chunk : chunks) {
    if (s_.sources[chunk].stage == ChunkStage::kAsked) {
      out_.line(s_.sources[chunk].path + ": taken in an earlier run, skipped");
      progress();
      continue;
    }
    if (s_.sources[chunk].stage == ChunkStage::kTrained) {  // killed before its questions
      if (auto r = ask({chunk}); !r) return rt::make_error(r.error().message);
      progress();
      continue;
    }
    const Dataset& d = *dataset(s_.sources[chunk].path).value();
    std::vector<learning::Group> groups;
    for (std::size_t k = 0; k < d.tracks.size(); ++k) {
      if (seen(chunk, k)) continue;
      const DatasetTrack& t = d.tracks[k];
      for (learning::Group& g :
           learning::cut_into_groups(chunk, k, t.segment_rows, t.holistic_rows, kSegDims, kHolDims,
                                     s_.induction.max_group_size))
        groups.push_back(std::move(g));
    }
    if (auto r = round(chunk, std::move(groups)); !r) return rt::make_error(r.error().message);
    if (auto r = ask({chunk}); !r) return rt::make_error(r.error().message);
    progress();
  }
  for (std::size_t r = 0; r < o_.rounds; ++r) {
    if (auto x = round(static_cast<std::uint32_t>(s_.sources.size()), {}); !x)
      return rt::make_error(x.error().message);
    progress();
  }
  if (o_.requery) {
    std::vector<std::uint32_t> unlabeled;
    for (std::uint32_t i = 0; i < s_.sources.size(); ++i)
      if (s_.sources[i].role == SourceRole::kUnlabeled) unlabeled.push_back(i);
    if (unlabeled.empty())
      return rt::make_error("--requery: the state has no unlabeled dataset to ask about");
    if (!s_.has_model)
      return rt::make_error("--requery: no round has run yet, so there is no model to ask with");
    if (auto r = ask(unlabeled); !r) return rt::make_error(r.error().message);
  }
  if (auto r = chart(); !r) return rt::make_error(r.error().message);
  if (!o_.export_dir.empty()) {
    if (auto r = export_labels(); !r) return rt::make_error(r.error().message);
  }
  if (!o_.out.empty()) {
    if (!s_.has_model)
      return rt::make_error("no round has run yet: there is no model to write to " + o_.out);
    if (auto m = write_model_file(o_.out, s_.model); !m) return rt::make_error(m.error().message);
  }
  out_.line(formatted("state %s: %u rounds, %zu user labels, %zu groups in the buffer; model %s",
                      dir_.c_str(), s_.rounds, s_.labels.size(), s_.buffer.size(),
                      s_.has_model ? (dir_ / "model.stacmodel").c_str() : "(none yet)"));
  return {};
}

}  // namespace

rt::Status run_session(const SessionOptions& options, const SessionOutput& given) {
  const SessionOutput output{given.line ? given.line : [](const std::string&) {},
                             given.warning ? given.warning : [](const std::string&) {},
                             given.progress ? given.progress : [](std::size_t, std::size_t) {}};
  return Inductor(options, output).run();
}

}  // namespace stac::induction
