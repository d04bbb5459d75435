// Histogram of oriented gradients of one window that is one block (the thesis's HOG arrays:
// window = block, so the 10x10 block stride never moves a block), computed as OpenCV's
// cv::HOGDescriptor does with derivAperture 1, unsigned gradients, gammaCorrection off, the
// default Gaussian block weighting (sigma = (block w + block h) / 8), trilinear interpolation
// into cells and bins, and L2-Hys block normalisation. Allocation-free after construction.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

namespace stac::descriptors {

struct HogShape {
  int width = 30, height = 30;  // window = block (px)
  int cell = 5;                 // square cells (px); width and height are multiples of it
  int bins = 6;                 // unsigned orientation bins over [0, pi)
  float l2hys_clip = 0.2f;
  [[nodiscard]] std::size_t size() const noexcept {
    return static_cast<std::size_t>(width / cell) * static_cast<std::size_t>(height / cell) *
           static_cast<std::size_t>(bins);
  }
};

// Per-pixel gradients of one image, computed for the whole image by reset() and kept until
// the next one: central differences [-1 0 1] with reflect-101 borders (OpenCV's convention),
// magnitude split between the two nearest orientation bins. Only the pixels with a gradient
// are kept, row by row in column order (an intensity view is mostly empty), so a window visits
// those alone, in the order a dense scan of its pixels would.
class GradientCache {
 public:
  // Images of at most `max_pixels` pixels and `max_rows` rows.
  GradientCache(std::size_t max_pixels, std::size_t max_rows, int bins);
  // `pixels` row-major, `width` floats a row, width * height <= max_pixels, height <= max_rows.
  void reset(const float* pixels, int width, int height) noexcept {
    reset(pixels, width, height, 0, 0, width, height);
  }
  // The same when the gradient is known to be zero outside columns [x0, x1) and rows [y0, y1)
  // (an empty range: everywhere): only there is it computed, and only there do windows look.
  void reset(const float* pixels, int width, int height, int x0, int y0, int x1, int y1) noexcept;

  struct Gradient {
    float weight[2];  // magnitude shares of bin[0] and bin[1]; not both zero
    std::uint8_t bin[2];
    std::uint16_t x;  // column
  };
  // Row y's pixels with a gradient, by column (y in [y0(), y1()); other rows have none).
  [[nodiscard]] std::span<const Gradient> row(int y) const noexcept {
    const auto r = static_cast<std::size_t>(y - y0_);
    return {gradient_.data() + row_begin_[r], row_begin_[r + 1] - row_begin_[r]};
  }
  // Where gradients were computed (outside: zero).
  [[nodiscard]] int x0() const noexcept { return x0_; }
  [[nodiscard]] int y0() const noexcept { return y0_; }
  [[nodiscard]] int x1() const noexcept { return x1_; }
  [[nodiscard]] int y1() const noexcept { return y1_; }

 private:
  int bins_ = 6;
  int x0_ = 0, y0_ = 0, x1_ = 0, y1_ = 0;
  std::vector<Gradient> gradient_;  // the rows' gradients, one after the other
  std::vector<std::uint32_t>
      row_begin_;  // row y's are [row_begin_[y - y0], row_begin_[y - y0 + 1])
  // One row's work, element by element (rows of at most min(max_pixels, 65536) pixels: a
  // column fits in the Gradient's 16 bits).
  static constexpr std::size_t kMaxRowPixels = 65536;
  std::vector<float> dx_, dy_, w0_, w1_;
  std::vector<int> bin_;
  std::vector<std::uint16_t> x_;
};

class HogWindow {
 public:
  explicit HogWindow(const HogShape& shape);
  // The descriptor (shape.size() floats, OpenCV's order: cells column-major - cell (cx, cy) at
  // (cx * cells_high + cy) * bins) of the window with top-left (x0, y0); the window must lie in
  // the image of `gradients`.
  void compute(const GradientCache& gradients, int x0, int y0, float* out) const noexcept;
  [[nodiscard]] const HogShape& shape() const noexcept { return shape_; }

 private:
  struct Share {
    std::uint16_t offset[4];  // histogram offsets of up to 4 cells
    float weight[4];          // Gaussian x bilinear weights (0 for unused)
    int cells;                // how many are used (a pixel near the block's edge: 1 or 2)
  };
  HogShape shape_;
  std::vector<Share> shares_;  // per window pixel, row-major
};

}  // namespace stac::descriptors
