// What the libFuzzer harnesses share: the shipped files they start from and a scratch file for
// parsers that read a path.
#pragma once

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

namespace stac::fuzz {

// A file of the source tree (config/, ../shared/data) by its path from the repository root.
inline std::filesystem::path source_file(const std::string& relative) {
  return std::filesystem::path(STAC_SOURCE_DIR) / relative;
}

// The input written to a file of this process's own (name ending in `suffix`), for loaders that
// take a path and decide the format by the name.
inline std::filesystem::path as_file(const std::uint8_t* data, std::size_t size,
                                     const std::string& suffix) {
  const std::filesystem::path p =
      std::filesystem::temp_directory_path() / ("stac_fuzz_" + std::to_string(getpid()) + suffix);
  std::ofstream(p, std::ios::binary | std::ios::trunc)
      .write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  return p;
}

}  // namespace stac::fuzz
