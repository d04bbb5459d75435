// Synthetic scenes for the segmentation tests: KITTI-style float4 clouds (x, y, z, intensity)
// of a ground surface and solid objects sampled on their surfaces, sensor 1.73 m above ground.
#pragma once

#include <cmath>
#include <functional>
#include <vector>

#include "perception/segmentation/segmenter.hpp"

namespace stac::testing {

constexpr float kSensorHeight = 1.73f;

struct Scene {
  std::vector<float> xyzi;

  void add(float x, float y, float z) { xyzi.insert(xyzi.end(), {x, y, z, 0.5f}); }
  [[nodiscard]] segmentation::PointView view() const {
    return {xyzi.data(), xyzi.size() / 4, 4 * sizeof(float)};
  }
  [[nodiscard]] std::size_t size() const { return xyzi.size() / 4; }

  // Ground over [-half, half]^2 every step metres; height(x, y) above the flat road.
  void ground(float half, float step, const std::function<float(float, float)>& height) {
    for (float x = -half; x <= half; x += step) {
      for (float y = -half; y <= half; y += step) add(x, y, -kSensorHeight + height(x, y));
    }
  }
  void flat_ground(float half = 15.0f) {
    ground(half, 0.1f, [](float, float) { return 0.0f; });
  }
  // Axis-aligned box standing on flat ground: its four sides and top, every step metres.
  void box(float cx, float cy, float length, float width, float height, float step = 0.05f) {
    const float x0 = cx - length / 2, x1 = cx + length / 2, y0 = cy - width / 2,
                y1 = cy + width / 2;
    const float zb = -kSensorHeight, zt = zb + height;
    for (float z = zb + step; z <= zt; z += step) {
      for (float x = x0; x <= x1; x += step) add(x, y0, z), add(x, y1, z);
      for (float y = y0; y <= y1; y += step) add(x0, y, z), add(x1, y, z);
    }
    for (float x = x0; x <= x1; x += step) {
      for (float y = y0; y <= y1; y += step) add(x, y, zt);
    }
  }
  // Vertical cylinder (a pedestrian) standing on flat ground.
  void cylinder(float cx, float cy, float radius, float height, float step = 0.05f) {
    const int around = static_cast<int>(2 * M_PI * radius / step) + 1;
    for (float z = -kSensorHeight + step; z <= -kSensorHeight + height; z += step) {
      for (int k = 0; k < around; ++k) {
        const double a = 2 * M_PI * k / around;
        add(cx + radius * static_cast<float>(std::cos(a)),
            cy + radius * static_cast<float>(std::sin(a)), z);
      }
    }
  }
};

}  // namespace stac::testing
