// stac induct: group induction on a state folder (perception/induction/session.hpp does the work).
#include <cstdio>
#include <memory>
#include <string>

#include "perception/induction/session.hpp"
#include "tools/commands.hpp"
#include "tools/support/progress.hpp"

namespace stac::tools {

void add_induct_command(CLI::App& app) {
  auto o = std::make_shared<induction::SessionOptions>();
  CLI::App* cmd = app.add_subcommand(
      "induct", "Teach the classifier with a few labels and unlabeled drives (group induction)");
  cmd->description(
      "Group induction (thesis ch. 2, docs/learning.md). A state folder (--state) keeps the\n"
      "user's labels, the background set B0, a bounded buffer of unlabeled groups and the model.\n"
      "Each --unlabeled dataset is one chunk of the stream and one round: its tracks are cut into\n"
      "groups of at most --group-size segments, every group in the buffer is inducted (labelled\n"
      "with the class whose exponential loss beats 'no label', against worst-case noise --eps) or\n"
      "not, the buffer keeps its most useful --buffer groups, and both boosting classifiers are\n"
      "trained on the labels, B0 and the inducted groups, warm-started (the model stays a fixed\n"
      "table: classifying never costs more). After a round the least confident tracks and the\n"
      "confident positives never shown are written to DIR/queries.jsonl; answers appended to\n"
      "DIR/labels.jsonl (`stac label`, or --oracle from the datasets' truth) trigger\n"
      "retrospection: de-induction of groups less confident than the worst new mistake, and a\n"
      "reset of the classifier. Every round writes DIR/model.stacmodel (usable by stac process,\n"
      "eval --classes and run), DIR/models/round-N.stacmodel and a line of DIR/history.jsonl;\n"
      "DIR/state.bin is replaced atomically, so a kill loses at most the round in progress.");
  cmd->add_option("--state", o->state, "the state folder (created on first use)")->required();
  cmd->add_option("--classes", o->classes,
                  "a new state's classes, comma-separated (e.g. car,pedestrian,bicyclist)");
  cmd->add_option("--model", o->model, "a new state starts from this model (warm start)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--add-classes", o->add_classes,
                  "with --model: new classes, comma-separated (e.g. pole), taught beside the "
                  "model's, which are kept as they are (not trained, reset or asked about)");
  cmd->add_option("--background", o->background,
                  "dataset of drives without the taught classes: B0, labelled background "
                  "automatically (repeatable)");
  cmd->add_option("--labels", o->labels,
                  "labelled dataset the user's first labels are taken from (repeatable)");
  cmd->add_option("--labels-per-class", o->labels_per_class,
                  "labels taken per class (and of background) from --labels; 0: all")
      ->check(CLI::Range(std::size_t{0}, std::size_t{1'000'000}));
  cmd->add_option("--unlabeled", o->unlabeled,
                  "dataset whose tracks are unlabeled data: one chunk and one round each "
                  "(repeatable; its labels are read only by --oracle)");
  cmd->add_option("--rounds", o->rounds, "rounds on the buffer after the chunks")
      ->check(CLI::Range(std::size_t{0}, std::size_t{100'000}));
  cmd->add_option("--ask", o->ask,
                  "questions per class after each chunk about its least confident tracks (and, "
                  "unless --ask-confident says otherwise, as many about confident positives)")
      ->capture_default_str()
      ->check(CLI::Range(std::size_t{0}, std::size_t{10'000}));
  cmd->add_option("--ask-confident", o->ask_confident,
                  "questions per class about the most confident positives the user has not seen "
                  "(default: --ask; 0: only the least confident, as the thesis's user was asked)")
      ->check(CLI::Range(std::size_t{0}, std::size_t{10'000}));
  cmd->add_flag("--requery", o->requery,
                "after the rounds, write new questions about the tracks of every unlabeled dataset "
                "of the state (what `stac label` runs after each batch of answers)");
  cmd->add_flag("--oracle", o->oracle,
                "a simulated user: answer the questions from the chunks' truth labels");
  cmd->add_option("--eval", o->eval,
                  "labelled held-out dataset: accuracy after each round, in history.jsonl "
                  "(repeatable)");
  auto* dual = cmd->add_flag("--dual", o->dual,
                             "dual induction: groups may be inducted as negatives (background)");
  auto* eps = cmd->add_option("--eps", o->eps, "worst-case classifier noise eps_max (log odds)")
                  ->capture_default_str()
                  ->check(CLI::Range(0.0, 100.0));
  auto* group = cmd->add_option("--group-size", o->group_size, "segments per group")
                    ->capture_default_str()
                    ->check(CLI::Range(std::size_t{1}, std::size_t{1000}));
  auto* buffer = cmd->add_option("--buffer", o->buffer, "unlabeled groups kept")
                     ->capture_default_str()
                     ->check(CLI::Range(std::size_t{1}, std::size_t{10'000'000}));
  cmd->add_option("--warm-rounds", o->warm_rounds, "boosting rounds added per round")
      ->capture_default_str()
      ->check(CLI::Range(std::size_t{1}, std::size_t{1'000'000}));
  cmd->add_option("--reset-rounds", o->reset_rounds,
                  "boosting rounds after a reset (the first round, retrospection)")
      ->capture_default_str()
      ->check(CLI::Range(std::size_t{1}, std::size_t{1'000'000}));
  cmd->add_option("--seed", o->seed, "seed of the first labels' draw and of boosting")
      ->capture_default_str();
  cmd->add_option("--out", o->out, "also write the final model to this file");
  cmd->add_option("--export", o->export_dir,
                  "write the user's labels and B0 as a dataset folder (for `stac train`)");
  cmd->add_flag("--baseline", o->baseline,
                "with --eval: also train on the same user labels and B0 without induction after "
                "each round, and report its accuracy beside");
  cmd->add_option("--reference", o->references,
                  "NAME=ACCURACY: a line on DIR/learning.png (repeatable)");

  cmd->callback([o, dual, eps, group, buffer] {
    o->dual_given = dual->count() > 0;
    o->eps_given = eps->count() > 0;
    o->group_given = group->count() > 0;
    o->buffer_given = buffer->count() > 0;
    Progress progress("induct: rounds", 1.0);
    const induction::SessionOutput output{
        [](const std::string& line) {
          std::printf("%s\n", line.c_str());
          std::fflush(stdout);
        },
        [](const std::string& warning) { std::fprintf(stderr, "stac: %s\n", warning.c_str()); },
        [&](std::size_t done, std::size_t total) {
          progress.set_total(static_cast<double>(total));
          progress.update(static_cast<double>(done));
          if (done == total) progress.finish();
        }};
    if (auto r = induction::run_session(*o, output); !r)
      throw CLI::RuntimeError(fail(r.error().message));
  });
}

}  // namespace stac::tools
