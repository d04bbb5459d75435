// Bird's-eye pictures of a scan (PNG, through OpenCV): the view from above, x forward = up in the
// picture, y left = left, with range rings every 10 m and a legend. Tools only, never per scan
// in the real-time loop.
#pragma once

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

#include "pictures/drawing.hpp"
#include "rt/expected.hpp"

namespace stac::pictures {

struct BirdsEyeOptions {
  double range_m = 50.0;  // half width of the picture
  int size_px = 900;      // square picture side
  double z_min_m = -2.5;  // colour scale of heights (sensor frame)
  double z_max_m = 2.5;
  bool height_bar = true;  // draw the height colour bar (off when points are coloured otherwise)
};

class BirdsEye {
 public:
  explicit BirdsEye(const BirdsEyeOptions& options);

  // A point coloured by its height.
  void add_point(float x, float y, float z) noexcept;
  // A point in a given colour.
  void add_point(float x, float y, Bgr colour) noexcept;
  // An oriented rectangle: centre (m), length along yaw (rad, from x), width across.
  void add_box(float cx, float cy, float length, float width, float yaw, Bgr colour);
  // A polyline through points (m), e.g. a track's path.
  void add_path(std::span<const PointM> points_m, Bgr colour, int thickness_px = 1);
  // A short text next to a point (m), e.g. a track id.
  void add_label(float x, float y, const std::string& text, Bgr colour);
  // A text line in the legend (top left).
  void add_legend(const std::string& line);
  rt::Status save(const std::filesystem::path& png) const;

 private:
  BirdsEyeOptions options_;
  double px_per_m_;
  std::vector<std::uint8_t> image_;  // size_px x size_px, 3 bytes (Bgr) a pixel
  int legend_lines_ = 0;
};

}  // namespace stac::pictures
