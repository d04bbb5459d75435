// stac train: a track classifier (segment and holistic boosting, ADBF weights) from `stac dataset`
// folders, written as a model file (docs/classification.md).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "formats/dataset_file.hpp"
#include "formats/model_file.hpp"
#include "perception/learning/track_training.hpp"
#include "tools/commands.hpp"
#include "tools/support/progress.hpp"

namespace stac::tools {

using namespace stac::formats;
namespace {

struct TrainOptions {
  std::vector<std::string> data;
  std::string out;
  std::uint64_t seed = 1;
  std::size_t rounds = 1000;
  double held_out = 0.3;
  std::size_t ensemble = 1;
  bool keep_inconsistent = false;
};

int run_train(const TrainOptions& o) {
  Dataset all;
  {
    Progress progress("train: reading", static_cast<double>(o.data.size()));
    for (std::size_t i = 0; i < o.data.size(); ++i) {
      auto d = read_labelled_dataset(o.data[i], "stac train");
      if (!d) return fail(d.error().message);
      if (auto a = append_dataset(all, std::move(*d), o.data[i]); !a)
        return fail(a.error().message);
      progress.update(static_cast<double>(i + 1));
    }
  }
  if (all.tracks.empty()) return fail("the datasets hold no track: nothing to train on");
  std::vector<learning::TrackExample> examples;
  examples.reserve(all.tracks.size());
  const classification::ClassNames& names = all.classes;
  const std::size_t classes = names.size();
  std::vector<std::size_t> per(classes + 1, 0);  // per class, then background
  const auto name = [&names](std::size_t c) {
    return classification::class_name(names, static_cast<classification::ClassIndex>(c));
  };
  std::size_t inconsistent = 0;
  for (DatasetTrack& t : all.tracks) {
    if (!o.keep_inconsistent && !consistent(t)) {
      ++inconsistent;
      continue;
    }
    ++per[t.label == classification::kBackground ? classes : t.label];
    examples.push_back(track_example(std::move(t)));
  }
  if (examples.empty())
    return fail(
        "every track of the datasets is inconsistent: nothing to train on "
        "(--keep-inconsistent trains on them)");
  // A class without tracks cannot be learned: none of them is an error, one missing a warning.
  std::string listed, foreground;
  for (std::size_t c = 0; c < classes; ++c) {
    listed += std::string(name(c)) + " " + std::to_string(per[c]) + ", ";
    foreground += std::string(c == 0 ? "" : c + 1 == classes ? " or " : ", ") + name(c);
  }
  if (std::count(per.begin(), per.end() - 1, std::size_t{0}) ==
      static_cast<std::ptrdiff_t>(classes)) {
    return fail("the datasets hold " + std::to_string(per[classes]) + " background tracks and no " +
                foreground +
                ": nothing to tell apart "
                "(add drives with objects: stac sim --scenario urban, then stac dataset)");
  }
  for (std::size_t k = 0; k < classes; ++k) {
    if (per[k] == 0) {
      std::fprintf(stderr, "stac train: warning: no %s track: the model will never say %s\n",
                   name(k), name(k));
    }
  }
  learning::TrackTrainingConfig config;
  config.segment.rounds = o.rounds;
  config.holistic.rounds = o.rounds;
  config.segment.seed = o.seed;
  config.holistic.seed = o.seed + 1;
  config.split_seed = o.seed;
  config.held_out_fraction = o.held_out;
  config.ensemble = o.ensemble;
  std::fprintf(stderr,
               "stac train: %zu tracks (%sbackground %zu; %zu inconsistent left out), %zu "
               "rounds%s...\n",
               examples.size(), listed.c_str(), per[classes], inconsistent, o.rounds,
               o.ensemble > 1 ? (" x " + std::to_string(o.ensemble) + " seeds").c_str() : "");
  const auto t0 = std::chrono::steady_clock::now();
  Progress progress("train: boosting", 1.0);
  config.progress = [&progress](double f) { progress.update(f); };
  auto model =
      learning::train_track_classifier(examples, names, classification::build_layouts(), config);
  progress.finish();
  if (!model) return fail("training failed: " + model.error().message);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (auto w = write_model_file(o.out, *model); !w) return fail(w.error().message);
  std::printf("%s: trained on %zu tracks (held out %.0f%% for the ADBF weights) in %.1f s\n",
              o.out.c_str(), examples.size(), 100.0 * o.held_out, seconds);
  const classification::AdbfParams& p = model->adbf;
  for (std::size_t c = 0; c < classes; ++c) {
    std::printf(
        "  %-10s prior(seg) %+.2f  prior(hol) %+.2f  adbf alpha %+.3f beta %+.3f gamma %+.3f\n",
        name(c), static_cast<double>(model->segment.model().prior[c]),
        static_cast<double>(model->holistic.model().prior[c]), static_cast<double>(p.alpha[c]),
        static_cast<double>(p.beta[c]), static_cast<double>(p.gamma[c]));
  }
  return 0;
}

}  // namespace

void add_train_command(CLI::App& app) {
  auto o = std::make_shared<TrainOptions>();
  CLI::App* cmd =
      app.add_subcommand("train", "Train the track classifier on `stac dataset` folders");
  cmd->description(
      "Reads the datasets, trains the segment and holistic boosting classifiers on one part of\n"
      "the tracks and the augmented discrete Bayes filter's weights on the held-out rest\n"
      "(learning::train_track_classifier), and writes the model file.");
  cmd->add_option("--data", o->data, "dataset folder written by `stac dataset` (repeatable)")
      ->required();
  cmd->add_option("--out", o->out, "output: the model file")->required();
  cmd->add_option("--seed", o->seed, "seed of the split and of boosting")->capture_default_str();
  cmd->add_option("--rounds", o->rounds, "boosting rounds of each classifier")
      ->capture_default_str()
      ->check(CLI::Range(std::size_t{1}, std::size_t{1000000}));
  cmd->add_option("--held-out", o->held_out, "fraction of tracks kept for the ADBF weights")
      ->capture_default_str()
      ->check(CLI::Range(0.05, 0.95));
  cmd->add_option("--ensemble", o->ensemble,
                  "boosting runs per classifier with different seeds, averaged into one table "
                  "(training takes N times as long; classifying costs the same)")
      ->capture_default_str()
      ->check(CLI::Range(std::size_t{1}, std::size_t{64}));
  cmd->add_flag("--keep-inconsistent", o->keep_inconsistent,
                "train on the inconsistent tracks too (more than 10% of their segments tracking "
                "or under-segmentation errors; the thesis leaves them out)");
  cmd->callback([o] {
    if (const int code = run_train(*o); code != 0) throw CLI::RuntimeError(code);
  });
}

}  // namespace stac::tools
