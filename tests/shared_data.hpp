// Where the tests find ../shared/data, and a skip that says why when it is absent.
#pragma once

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "test_paths.hpp"

namespace stac::testing {

inline std::filesystem::path shared_data(const std::string& relative) {
  return std::filesystem::path(::stac::testing::shared_data_dir()) / relative;
}

// A KITTI velodyne .bin of shared/data (float32 x, y, z, reflectance per point); empty when absent.
inline std::vector<float> read_kitti_bin(const std::string& relative) {
  std::ifstream f(shared_data(relative), std::ios::binary | std::ios::ate);
  if (!f) return {};
  std::vector<float> v(static_cast<std::size_t>(f.tellg()) / sizeof(float));
  f.seekg(0);
  f.read(reinterpret_cast<char*>(v.data()), static_cast<std::streamsize>(v.size() * sizeof(float)));
  return v;
}

}  // namespace stac::testing

// Skips the current test, naming the missing file, when shared/data is not beside the checkout.
#define STAC_REQUIRE_SHARED_DATA(relative_path)                                  \
  do {                                                                           \
    if (!std::filesystem::exists(::stac::testing::shared_data(relative_path))) { \
      GTEST_SKIP() << "SKIPPED: " << ::stac::testing::shared_data(relative_path) \
                   << " is absent (shared/data must sit beside the checkout)";   \
    }                                                                            \
  } while (0)
