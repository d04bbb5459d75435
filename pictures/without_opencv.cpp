// The pictures' interface in a build without OpenCV (cmake -DSTAC_PICTURES=OFF; drawing.hpp):
// `stac` refuses the options that ask for a picture before any work (needs_pictures), and a
// report's pictures are left out: each save writes no file, tells once on stderr which picture
// was the first left out and why, and succeeds, so that the report's numbers and tables are
// written as ever. .ci/no-pictures builds this variant and checks both.
#include <atomic>
#include <cstdio>

#include "pictures/birds_eye.hpp"
#include "pictures/chart.hpp"
#include "pictures/demo_pictures.hpp"
#include "pictures/drawing.hpp"

namespace stac::pictures {
namespace {

rt::Status left_out(const std::filesystem::path& png) {
  static std::atomic<bool> told{false};
  if (!told.exchange(true)) {
    std::fprintf(stderr, "stac: pictures are left out (%s), from %s on\n", kWithoutPicturesHint,
                 png.string().c_str());
  }
  return {};
}

}  // namespace

bool pictures_built() noexcept {
  return false;
}

Bgr segment_colour(std::size_t) {
  return {};
}

rt::Status save_bar_chart(const std::filesystem::path& png, const std::string&,
                          const std::vector<std::string>&, const std::vector<std::string>&,
                          const std::vector<std::vector<double>>&, double) {
  return left_out(png);
}

rt::Status save_confusion_matrix(const std::filesystem::path& png, const std::string&,
                                 const std::vector<std::string>&,
                                 const std::vector<std::vector<std::uint64_t>>&) {
  return left_out(png);
}

rt::Status save_side_by_side(const std::filesystem::path&, const std::filesystem::path&,
                             const std::filesystem::path& png) {
  return left_out(png);
}

rt::Status save_chart(const Chart&, const std::filesystem::path& png) {
  return left_out(png);
}

rt::Status draw_drive(const DriveView&, DrivePicture, const std::filesystem::path& png) {
  return left_out(png);
}

// Nothing is drawn, so the picture holds no pixels.
BirdsEye::BirdsEye(const BirdsEyeOptions& options) : options_(options), px_per_m_(0.0) {}
void BirdsEye::add_point(float, float, float) noexcept {}
void BirdsEye::add_point(float, float, Bgr) noexcept {}
void BirdsEye::add_box(float, float, float, float, float, Bgr) {}
void BirdsEye::add_path(std::span<const PointM>, Bgr, int) {}
void BirdsEye::add_label(float, float, const std::string&, Bgr) {}
void BirdsEye::add_legend(const std::string&) {}
rt::Status BirdsEye::save(const std::filesystem::path& png) const {
  return left_out(png);
}

}  // namespace stac::pictures
