// Group induction as a resumable workflow on a state folder (thesis ch. 2; docs/learning.md), what
// `stac induct` runs and `stac label` starts after each batch of answers. The folder keeps the
// user's labels, the background set B0, the buffer of unlabeled groups and the model; each
// unlabeled dataset given is one chunk of the stream and one round (induction phase, then
// warm-started training); after a round the tracks the model is least sure of (and its confident
// positives the user has never seen) are written as questions, answered by the user (`stac label`,
// or labels.jsonl by hand) or, with `oracle`, from the datasets' truth.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "rt/expected.hpp"

namespace stac::induction {

// What a session does, as `stac induct`'s options say it (each field is the option of its name).
struct SessionOptions {
  std::string state;
  std::string classes;      // comma-separated, for a new state
  std::string model;        // a model to start a new state from
  std::string add_classes;  // comma-separated classes taught beside the model's, kept as they are
  std::vector<std::string> background, labels, unlabeled, eval;
  std::size_t labels_per_class = 0;          // 0: every track of the --labels datasets
  std::size_t rounds = 0;                    // extra rounds on the buffer after the chunks
  std::size_t ask = 5;                       // least-confident questions per class a round
  std::optional<std::size_t> ask_confident;  // confident-positive questions (default: ask)
  bool oracle = false;
  bool requery = false;  // after the rounds: new questions over every unlabeled dataset
  bool dual = false;
  double eps = 0.0;
  std::size_t group_size = 10, buffer = 20'000;
  std::size_t warm_rounds = 200, reset_rounds = 1000;
  std::uint64_t seed = 1;
  std::string out;
  std::string export_dir;
  std::vector<std::string> references;  // NAME=ACCURACY lines on the chart
  // Which of --dual, --eps, --group-size, --buffer were given (each is checked against a state's).
  bool dual_given = false, eps_given = false, group_given = false, buffer_given = false;
  bool baseline = false;
};

// What a session tells the person running it (each optional).
struct SessionOutput {
  std::function<void(const std::string&)> line;     // a line of its summary (a round, a skip)
  std::function<void(const std::string&)> warning;  // something it repaired (a torn last line)
  std::function<void(std::size_t done, std::size_t total)> progress;  // rounds done of total
};

// Opens (or creates) options.state, takes its lock, reads the answers written since, runs a round
// per new chunk and options.rounds more, asks, and writes the model, the chart and the history.
// An error says what to fix; a kill at any moment loses at most the round in progress.
rt::Status run_session(const SessionOptions& options, const SessionOutput& output);

}  // namespace stac::induction
