// What the libFuzzer harnesses share: the shipped files they start from.
#pragma once

#include <filesystem>
#include <string>

#include "settings/build_tree.hpp"

namespace stac::fuzz {

// A file of the source tree (config/, ../shared/data) by its path from the repository root.
inline std::filesystem::path source_file(const std::string& relative) {
  return std::filesystem::path(stac::settings::kSourceDir) / relative;
}

}  // namespace stac::fuzz
