// What the libFuzzer harnesses share: the shipped files they start from.
#pragma once

#include <filesystem>
#include <string>

namespace stac::fuzz {

// A file of the source tree (config/, ../shared/data) by its path from the repository root.
inline std::filesystem::path source_file(const std::string& relative) {
  return std::filesystem::path(STAC_SOURCE_DIR) / relative;
}

}  // namespace stac::fuzz
