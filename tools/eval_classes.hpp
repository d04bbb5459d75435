// `stac eval --classes`: Table 1.2 of the thesis on `stac dataset` folders with a trained model
// (docs/classification.md "Evaluation").
#pragma once

#include <string>
#include <vector>

namespace stac::tools {

struct ClassEvalOptions {
  std::vector<std::string> data;
  std::string model, report;
};

// Prints the table; with a report folder also metrics.json, confusion.png and pr.png. Returns the
// process exit code (messages on stderr).
int run_class_eval(const ClassEvalOptions& o);

}  // namespace stac::tools
