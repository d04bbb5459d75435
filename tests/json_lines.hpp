// A JSON lines file (labels.jsonl, queries.jsonl, history.jsonl, ...) as tests read it: one
// object per non-empty line; a line that is not JSON throws, so the test fails at it.
#pragma once

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace stac::testing {

inline std::vector<nlohmann::json> read_json_lines(const std::filesystem::path& p) {
  std::vector<nlohmann::json> out;
  std::ifstream in(p);
  for (std::string line; std::getline(in, line);)
    if (!line.empty()) out.push_back(nlohmann::json::parse(line));
  return out;
}

}  // namespace stac::testing
