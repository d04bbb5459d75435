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
  // Axis-aligned box on flat ground, from `bottom` up to `height` above it: its four sides and
  // top, every step metres.
  void box(float cx, float cy, float length, float width, float height, float step = 0.05f,
           float bottom = 0.0f) {
    const float x0 = cx - length / 2, x1 = cx + length / 2, y0 = cy - width / 2,
                y1 = cy + width / 2;
    const float zb = -kSensorHeight + bottom, zt = -kSensorHeight + height;
    for (float z = zb + step; z <= zt; z += step) {
      for (float x = x0; x <= x1; x += step) add(x, y0, z), add(x, y1, z);
      for (float y = y0; y <= y1; y += step) add(x0, y, z), add(x1, y, z);
    }
    for (float x = x0; x <= x1; x += step) {
      for (float y = y0; y <= y1; y += step) add(x, y, zt);
    }
  }
  // Vertical cylinder (a pedestrian) on flat ground, from `bottom` up to `height` above it.
  void cylinder(float cx, float cy, float radius, float height, float step = 0.05f,
                float bottom = 0.0f) {
    const int around = static_cast<int>(2 * M_PI * radius / step) + 1;
    for (float z = -kSensorHeight + bottom + step; z <= -kSensorHeight + height; z += step) {
      for (int k = 0; k < around; ++k) {
        const double a = 2 * M_PI * k / around;
        add(cx + radius * static_cast<float>(std::cos(a)),
            cy + radius * static_cast<float>(std::sin(a)), z);
      }
    }
  }
  // A person walking along x: legs apart in a stride (0..0.85 m), torso to height - 0.3 m, head,
  // hands at the sides (0.8..1.15 m).
  void walker(float cx, float cy, float height = 1.75f, float stride = 0.8f) {
    box(cx, cy, stride, 0.3f, 0.85f);
    cylinder(cx, cy, 0.2f, height - 0.3f, 0.05f, 0.85f);
    cylinder(cx, cy, 0.1f, height, 0.05f, height - 0.3f);
    for (float z = 0.8f; z <= 1.15f; z += 0.05f) {
      add(cx, cy - 0.28f, -kSensorHeight + z);
      add(cx, cy + 0.28f, -kSensorHeight + z);
    }
  }
  // A sedan along x: body 0..0.9 m, a narrower cabin on it up to 1.45 m.
  void sedan(float cx, float cy) {
    box(cx, cy, 4.5f, 1.8f, 0.9f);
    box(cx - 0.3f, cy, 2.3f, 1.5f, 1.45f, 0.05f, 0.9f);
  }
};

}  // namespace stac::testing
