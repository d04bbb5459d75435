#include "perception/descriptors/hog.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "perception/descriptors/fast_math.hpp"

namespace stac::descriptors {
namespace {

// Reflect-101 index (OpenCV BORDER_REFLECT_101) for one step outside [0, n).
int reflect(int i, int n) noexcept {
  if (n == 1) return 0;
  if (i < 0) return -i;
  if (i >= n) return 2 * n - 2 - i;
  return i;
}

}  // namespace

GradientCache::GradientCache(std::size_t max_pixels, std::size_t max_rows, int bins)
    : bins_(bins),
      gradient_(max_pixels),
      row_begin_(max_rows + 1, 0),
      dx_(std::min(max_pixels, kMaxRowPixels)),
      dy_(dx_.size()),
      w0_(dx_.size()),
      w1_(dx_.size()),
      bin_(dx_.size()),
      x_(dx_.size()) {}

void GradientCache::reset(const float* pixels, int width, int height, int x0, int y0, int x1,
                          int y1) noexcept {
  x0_ = std::clamp(x0, 0, width);
  x1_ = std::clamp(x1, x0_, width);
  y0_ = std::clamp(y0, 0, height);
  y1_ = std::clamp(y1, y0_, height);
  const float bins = static_cast<float>(bins_);
  const float to_position = bins / kPi;
  std::uint32_t kept = 0;
  float* const dxs = dx_.data();
  float* const dys = dy_.data();
  std::uint16_t* const xs = x_.data();
  for (int y = y0_; y < y1_; ++y) {
    row_begin_[static_cast<std::size_t>(y - y0_)] = kept;
    const float* row = pixels + static_cast<std::ptrdiff_t>(y) * width;
    const float* up = pixels + static_cast<std::ptrdiff_t>(reflect(y - 1, height)) * width;
    const float* down = pixels + static_cast<std::ptrdiff_t>(reflect(y + 1, height)) * width;
    // 1. The row's pixels with a gradient, side by side (dx, dy, column).
    int m = 0;
    for (int x = x0_; x < x1_; ++x) {
      const int left = x > 0 ? x - 1 : reflect(x - 1, width);
      const int right = x + 1 < width ? x + 1 : reflect(x + 1, width);
      const float dx = row[right] - row[left];
      const float dy = down[x] - up[x];
      dxs[m] = dx;
      dys[m] = dy;
      xs[m] = static_cast<std::uint16_t>(x);
      m += (dx != 0.0f || dy != 0.0f) ? 1 : 0;
    }
    // 2. Magnitude split between the two nearest bins: the same operations on every element,
    // without branches, so the compiler can do several at once (the same values as one by one).
    for (int i = 0; i < m; ++i) {
      const float dx = dxs[i], dy = dys[i];
      const float magnitude = std::sqrt(dx * dx + dy * dy);
      const float position = angle_of(dy, dx) * to_position - 0.5f;  // [-0.5, 2 bins)
      int bin = floor_index(position);
      const float fraction = position - static_cast<float>(bin);
      w0_[i] = magnitude * (1.0f - fraction);
      w1_[i] = magnitude * fraction;
      bin += bin < 0 ? bins_ : 0;
      bin -= bin >= bins_ ? bins_ : 0;
      bin_[i] = bin;
    }
    // 3. Kept in column order; an underflow to two zero weights adds nothing and is dropped.
    for (int i = 0; i < m; ++i) {
      if (w0_[i] == 0.0f && w1_[i] == 0.0f) continue;
      const int bin = bin_[static_cast<std::size_t>(i)];
      Gradient& g = gradient_[kept++];
      g.weight[0] = w0_[i];
      g.weight[1] = w1_[i];
      g.bin[0] = static_cast<std::uint8_t>(bin);
      g.bin[1] = static_cast<std::uint8_t>(bin + 1 == bins_ ? 0 : bin + 1);
      g.x = xs[i];
    }
  }
  row_begin_[static_cast<std::size_t>(y1_ - y0_)] = kept;
}

HogWindow::HogWindow(const HogShape& shape) : shape_(shape) {
  if (shape.cell <= 0 || shape.width % shape.cell != 0 || shape.height % shape.cell != 0 ||
      shape.bins <= 0 || shape.bins > 255 || shape.size() > 65535) {
    throw std::invalid_argument("HogShape: width and height must be multiples of cell, bins 1-255");
  }
  const int cells_x = shape.width / shape.cell, cells_y = shape.height / shape.cell;
  const float sigma = static_cast<float>(shape.width + shape.height) / 8.0f;
  const float scale = 1.0f / (2.0f * sigma * sigma);
  shares_.resize(static_cast<std::size_t>(shape.width) * static_cast<std::size_t>(shape.height));
  for (int y = 0; y < shape.height; ++y) {
    for (int x = 0; x < shape.width; ++x) {
      const float dy = static_cast<float>(y) - static_cast<float>(shape.height) * 0.5f;
      const float dx = static_cast<float>(x) - static_cast<float>(shape.width) * 0.5f;
      const float gauss = std::exp(-(dx * dx + dy * dy) * scale);
      // Bilinear between cell centres; shares of cells outside the block are dropped.
      const float cx = (static_cast<float>(x) + 0.5f) / static_cast<float>(shape.cell) - 0.5f;
      const float cy = (static_cast<float>(y) + 0.5f) / static_cast<float>(shape.cell) - 0.5f;
      const int x0 = static_cast<int>(floor_exact(cx)), y0 = static_cast<int>(floor_exact(cy));
      const float fx = cx - static_cast<float>(x0), fy = cy - static_cast<float>(y0);
      Share& s = shares_[static_cast<std::size_t>(y) * static_cast<std::size_t>(shape.width) +
                         static_cast<std::size_t>(x)];
      int n = 0;
      for (int k = 0; k < 4; ++k) {
        const int ix = x0 + (k & 1), iy = y0 + (k >> 1);
        const float w = ((k & 1) ? fx : 1.0f - fx) * ((k >> 1) ? fy : 1.0f - fy);
        if (ix < 0 || ix >= cells_x || iy < 0 || iy >= cells_y) continue;
        s.offset[n] = static_cast<std::uint16_t>((ix * cells_y + iy) * shape.bins);
        s.weight[n] = w * gauss;
        ++n;
      }
      s.cells = n;
      for (; n < 4; ++n) {
        s.offset[n] = 0;
        s.weight[n] = 0.0f;
      }
    }
  }
}

void HogWindow::compute(const GradientCache& gradients, int x0, int y0, float* out) const noexcept {
  const std::size_t n = shape_.size();
  std::fill(out, out + n, 0.0f);
  // Only where gradients were computed: elsewhere they are zero and add nothing. Each row's
  // gradients come by column, so the window's pixels are visited in row-major order.
  const int ya = std::max(gradients.y0() - y0, 0),
            yb = std::min(gradients.y1() - y0, shape_.height);
  for (int y = ya; y < yb; ++y) {
    const std::span<const GradientCache::Gradient> row = gradients.row(y0 + y);
    const auto first = std::partition_point(
        row.begin(), row.end(), [x0](const GradientCache::Gradient& g) { return g.x < x0; });
    const Share* shares = shares_.data() + static_cast<std::ptrdiff_t>(y) * shape_.width;
    for (auto it = first; it != row.end() && it->x < x0 + shape_.width; ++it) {
      const GradientCache::Gradient& g = *it;
      const Share& s = shares[g.x - x0];
      // The unused shares would add exactly +0 (the histogram is never -0): skipped.
      for (int k = 0; k < s.cells; ++k) {
        float* h = out + s.offset[k];
        h[g.bin[0]] += s.weight[k] * g.weight[0];
        h[g.bin[1]] += s.weight[k] * g.weight[1];
      }
    }
  }
  // L2-Hys as OpenCV: scale by 1 / (|h| + 0.1 n), clip, scale by 1 / (|h| + 1e-3).
  float sum = 0.0f;
  for (std::size_t i = 0; i < n; ++i) sum += out[i] * out[i];
  float scale = 1.0f / (std::sqrt(sum) + 0.1f * static_cast<float>(n));
  sum = 0.0f;
  for (std::size_t i = 0; i < n; ++i) {
    out[i] = std::min(out[i] * scale, shape_.l2hys_clip);
    sum += out[i] * out[i];
  }
  scale = 1.0f / (std::sqrt(sum) + 1e-3f);
  for (std::size_t i = 0; i < n; ++i) out[i] *= scale;
}

}  // namespace stac::descriptors
