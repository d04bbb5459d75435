// The six real KITTI HDL-64E scans of shared/data (float32 x, y, z, reflectance), read once for
// the benchmarks; a benchmark cannot run without them, so their absence stops it with a message.
#pragma once

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "settings/build_tree.hpp"

namespace stac::benchmarks {

inline const std::vector<std::vector<float>>& kitti_scans() {
  static const std::vector<std::vector<float>> all = [] {
    std::vector<std::vector<float>> out;
    for (int i = 0; i < 6; ++i) {
      const auto path = std::filesystem::path(stac::settings::kSharedDataDir) /
                        ("kitti/00000" + std::to_string(i) + ".bin");
      std::ifstream f(path, std::ios::binary | std::ios::ate);
      if (!f) {
        std::fprintf(stderr, "%s is absent (shared/data must sit beside the checkout)\n",
                     path.c_str());
        std::exit(1);
      }
      std::vector<float> v(static_cast<std::size_t>(f.tellg()) / sizeof(float));
      f.seekg(0);
      f.read(reinterpret_cast<char*>(v.data()),
             static_cast<std::streamsize>(v.size() * sizeof(float)));
      out.push_back(std::move(v));
    }
    return out;
  }();
  return all;
}

}  // namespace stac::benchmarks
