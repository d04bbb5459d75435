// The plain types of the pictures' interfaces, so that no caller needs OpenCV, and the small
// drawings the reports share: a palette for segments, bar charts, confusion matrices, two
// pictures side by side. PNG files; every failure names the file.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "rt/expected.hpp"

namespace stac::pictures {

struct Bgr {  // a colour, in OpenCV's byte order
  std::uint8_t b = 0, g = 0, r = 0;
};
struct PointM {  // a point on the ground (m)
  float x = 0, y = 0;
};
struct Point3M {  // a point in space (m)
  float x = 0, y = 0, z = 0;
};

// False in a build without OpenCV (cmake -DSTAC_PICTURES=OFF). Then nothing is drawn: options
// that ask for a picture are refused (needs_pictures), and the pictures of a report are left
// out with one notice on stderr while its numbers and tables are written as ever.
bool pictures_built() noexcept;
inline constexpr const char* kWithoutPicturesHint =
    "cmake -DSTAC_PICTURES=OFF; configure with -DSTAC_PICTURES=ON and libopencv-dev for PNG "
    "pictures";

// Distinct, bright hues for segment i (a cycle of 180 hues).
Bgr segment_colour(std::size_t i);

// A bar chart of named series per group, values clamped to [lo, 1]; values[s][g] is series s in
// group g (NaN: no bar).
rt::Status save_bar_chart(const std::filesystem::path& png, const std::string& title,
                          const std::vector<std::string>& groups,
                          const std::vector<std::string>& series,
                          const std::vector<std::vector<double>>& values, double lo);

// A confusion matrix: counts[truth][predicted], rows and columns named, cells shaded by the row's
// share.
rt::Status save_confusion_matrix(const std::filesystem::path& png, const std::string& title,
                                 const std::vector<std::string>& names,
                                 const std::vector<std::vector<std::uint64_t>>& counts);

// Two PNG pictures of the same height next to each other.
rt::Status save_side_by_side(const std::filesystem::path& left, const std::filesystem::path& right,
                             const std::filesystem::path& png);

}  // namespace stac::pictures
