// Simulated drives and their datasets made once per build tree and shared by every test program
// that asks for the same ones (issue 51). ctest runs each test in its own process: a suite's
// SetUpTestSuite made its own copies of the same drives in every one of them (the five InductCli
// tests each spent about 25 s in `stac sim` and `stac dataset` before their first assertion).
//
// The first test to ask makes the drive under an exclusive lock (the others wait on it, then read
// it); a drive belongs to the `stac` binary that made it (its size and modification time name the
// folder), so a rebuilt `stac` makes them again and the old ones are removed. The files are the
// tests' inputs and read-only to them: a test that changes one works on its own copy.
#pragma once

#include <string>
#include <vector>

namespace stac::testing {

// A path, or why it could not be made (the command and its output).
struct Shared {
  std::string path;
  std::string error;
  explicit operator bool() const { return error.empty(); }
};

// BASE such that BASE.pcap and BASE.jsonl are what `stac sim SIM_ARGS --out BASE.pcap --truth
// BASE.jsonl` writes.
Shared shared_sim(const std::string& sim_args);

// The folder `stac dataset --in BASE.pcap [--truth BASE.jsonl] DATASET_ARGS --out FOLDER` writes
// for the drive shared_sim(SIM_ARGS) (with its truth when WITH_TRUTH: the tracks labelled).
Shared shared_dataset(const std::string& sim_args, bool with_truth,
                      const std::string& dataset_args = "");

// Several at once: those no other test is making first, then the others (waiting for them).
std::vector<Shared> shared_sims(const std::vector<std::string>& sims);
struct SharedDataset {
  std::string sim_args;
  bool with_truth = true;
  std::string dataset_args;
};
std::vector<Shared> shared_datasets(const std::vector<SharedDataset>& datasets);

// The folder OUT of `stac ARGS`, every "{out}" in ARGS replaced by OUT (a state `stac induct` made
// from shared datasets, say). ARGS is the key: they must name every input.
Shared shared_run(const std::string& args);
std::vector<Shared> shared_runs(const std::vector<std::string>& runs);

}  // namespace stac::testing
