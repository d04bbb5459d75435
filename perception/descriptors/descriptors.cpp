#include "perception/descriptors/descriptors.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "perception/descriptors/fast_math.hpp"
#include "perception/descriptors/hog.hpp"

namespace stac::descriptors {
namespace {

// Spin images about the vertical axis: (pixels per metre, rows, cols), as the original code.
struct SpinShape {
  float px_per_m;
  int rows, cols;
};
constexpr SpinShape kSpins[4] = {{3, 10, 10}, {7, 14, 7}, {10, 20, 10}, {5, 10, 5}};
constexpr int kMaxSpinCells = 200;  // the largest rows x cols above
static_assert([] {
  for (const SpinShape& s : kSpins) {
    if (s.rows * s.cols > kMaxSpinCells) return false;
  }
  return true;
}());

// HOG arrays: per view a small and a large window (= block), each at 4 (u, v) offsets.
constexpr int kViews = 3;
constexpr const char* kViewNames[kViews] = {"front", "side", "top"};
constexpr HogShape kHogShapes[kViews][2] = {{{15, 30, 5, 6, 0.2f}, {30, 30, 5, 6, 0.2f}},
                                            {{15, 30, 5, 6, 0.2f}, {30, 30, 5, 6, 0.2f}},
                                            {{15, 15, 5, 6, 0.2f}, {30, 30, 5, 6, 0.2f}}};
constexpr float kOffsets[4][2] = {{0.0f, 1.0f}, {0.5f, 0.0f}, {0.5f, 0.5f}, {1.0f, 1.0f}};
constexpr const char* kOffsetNames[4] = {"u0_v1", "u0.5_v0", "u0.5_v0.5", "u1_v1"};
constexpr std::size_t kMaxHogRaw = 216;  // 30x30 window, 5 px cells, 6 bins

// Names live as long as the program: built once into static strings.
struct Layout {
  std::array<std::string, kSpaceCount> names;
  std::array<Space, kSpaceCount> spaces;
  Layout() {
    std::size_t k = 0, offset = 0;
    auto add = [&](std::string name, std::size_t size) {
      names[k] = std::move(name);
      spaces[k] = Space{names[k], offset, size};
      offset += size;
      ++k;
    };
    add("bbox_size", 3);
    for (const SpinShape& s : kSpins) {
      add("spin_" + std::to_string(static_cast<int>(s.px_per_m)) + "ppm_" + std::to_string(s.rows) +
              "x" + std::to_string(s.cols),
          static_cast<std::size_t>(s.rows) * static_cast<std::size_t>(s.cols));
    }
    for (int v = 0; v < kViews; ++v) {
      for (const HogShape& h : kHogShapes[v]) {
        for (const char* o : kOffsetNames) {
          add(std::string("hog_") + kViewNames[v] + "_" + std::to_string(h.width) + "x" +
                  std::to_string(h.height) + "_" + o,
              kHogProjectedDim);
        }
      }
    }
    if (k != kSpaceCount || offset != kDimensions) throw std::logic_error("descriptor layout");
  }
};

const Layout& layout() {
  static const Layout l;
  return l;
}

// Deterministic standard normals (splitmix64 + Box-Muller): the same on every platform.
class Normal {
 public:
  explicit Normal(std::uint64_t seed) : state_(seed) {}
  double next() {
    if (has_spare_) {
      has_spare_ = false;
      return spare_;
    }
    const double u1 = (static_cast<double>(bits() >> 11) + 1.0) * 0x1.0p-53;  // (0, 1]
    const double u2 = static_cast<double>(bits() >> 11) * 0x1.0p-53;          // [0, 1)
    const double r = std::sqrt(-2.0 * std::log(u1));
    spare_ = r * std::sin(2.0 * M_PI * u2);
    has_spare_ = true;
    return r * std::cos(2.0 * M_PI * u2);
  }

 private:
  std::uint64_t bits() {
    std::uint64_t z = (state_ += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  std::uint64_t state_;
  double spare_ = 0.0;
  bool has_spare_ = false;
};

// A pixel rectangle, corners inclusive; empty when x1 < x0 or y1 < y0. The empty rectangle
// that unions start from has its first corner beyond the image ({w, h, -1, -1}).
struct Rect {
  int x0, y0, x1, y1;
  [[nodiscard]] bool empty() const noexcept { return x1 < x0 || y1 < y0; }
  [[nodiscard]] long area() const noexcept {
    return empty() ? 0 : static_cast<long>(x1 - x0 + 1) * static_cast<long>(y1 - y0 + 1);
  }
  [[nodiscard]] bool contains(int x, int y) const noexcept {
    return x >= x0 && x <= x1 && y >= y0 && y <= y1;
  }
  // Grown by `px` on every side, clipped to a w x h image (not empty).
  [[nodiscard]] Rect grown(int px, int w, int h) const noexcept {
    return {std::max(x0 - px, 0), std::max(y0 - px, 0), std::min(x1 + px, w - 1),
            std::min(y1 + px, h - 1)};
  }
  // The bounding box of both (either may be the empty {w, h, -1, -1}).
  [[nodiscard]] Rect united(const Rect& o) const noexcept {
    return {std::min(x0, o.x0), std::min(y0, o.y0), std::max(x1, o.x1), std::max(y1, o.y1)};
  }
  [[nodiscard]] Rect intersected(const Rect& o) const noexcept {
    return {std::max(x0, o.x0), std::max(y0, o.y0), std::min(x1, o.x1), std::min(y1, o.y1)};
  }
  bool operator==(const Rect&) const = default;
};

// Where a view's HOG windows go and which regions of the view are worked on.
struct ViewPlan {
  int w = 0, h = 0;
  float pad_w = 0.0f, pad_h = 0.0f;
  int placed[2][4][2] = {};  // per array, per offset: top-left
  Rect region[4] = {};       // the regions worked on
  int regions = 0;
  int region_of[4] = {};  // offset k's gradients are those of region region_of[k]
  Rect raw_rect[4] = {};  // per region: where the unsmoothed view is read (grown by 2 px)
};

// Zero mean, unit mean square; an all-equal vector becomes all zeros.
void whiten(float* v, std::size_t n) noexcept {
  double mean = 0.0;
  for (std::size_t i = 0; i < n; ++i) mean += v[i];
  mean /= static_cast<double>(n);
  double var = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const double d = v[i] - mean;
    var += d * d;
  }
  var /= static_cast<double>(n);
  const double scale = var > 0.0 ? 1.0 / std::sqrt(var) : 0.0;
  for (std::size_t i = 0; i < n; ++i) v[i] = static_cast<float>((v[i] - mean) * scale);
}

}  // namespace

const char* validate(const DescriptorConfig& c) noexcept {
  if (c.max_points < 1 || c.max_points > 10'000'000) return "max_points must be in [1, 1e7]";
  if (c.min_image_px < 30) return "min_image_px must be >= 30 (the largest HOG window)";
  if (c.max_image_px < c.min_image_px || c.max_image_px > 4096)
    return "max_image_px must be in [min_image_px, 4096]";
  if (!(c.image_px_per_m > 0.0 && c.image_px_per_m <= 1000.0))
    return "image_px_per_m must be in (0, 1000]";
  if (!(c.intensity_full_scale > 0.0) || !std::isfinite(c.intensity_full_scale))
    return "intensity_full_scale must be > 0";
  return "";
}

// The layout is built before any scan: DescriptorPipeline's constructor builds it, so the
// static below is already initialized when the per-scan path reads it and nothing can throw.
// NOLINTNEXTLINE(bugprone-exception-escape)
const std::array<Space, kSpaceCount>& spaces() noexcept {
  return layout().spaces;
}

struct DescriptorPipeline::State {
  explicit State(const DescriptorConfig& c)
      : x(c.max_points),
        y(c.max_points),
        z(c.max_points),
        value(c.max_points),
        pixel(c.max_points),
        row_index(c.max_points),
        radius(c.max_points),
        gradients(c.max_image_px * c.max_image_px, c.max_image_px, 6),
        windows{HogWindow(kHogShapes[0][0]), HogWindow(kHogShapes[0][1]),
                HogWindow(kHogShapes[2][0])} {
    const std::size_t pixels = c.max_image_px * c.max_image_px;
    for (int v = 0; v < kViews; ++v) images[v].assign(pixels, 0.0f);
    sum.assign(pixels, 0.0f);
    count.assign(pixels, 0.0f);
    smooth_tmp.assign(pixels, 0.0f);
    raw_image.assign(pixels, 0.0f);
    Normal normal(c.projection_seed);
    const double scale = 1.0 / std::sqrt(static_cast<double>(kHogProjectedDim));
    for (int v = 0; v < kViews; ++v) {
      for (int a = 0; a < 2; ++a) {
        // Drawn row by row (kHogProjectedDim x raw size) and stored transposed (raw size x
        // kHogProjectedDim), so the product below runs over contiguous outputs.
        auto& m = projection[v][a];
        const std::size_t raw_n = kHogShapes[v][a].size();
        m.resize(kHogProjectedDim * raw_n);
        for (std::size_t r = 0; r < kHogProjectedDim; ++r) {
          for (std::size_t j = 0; j < raw_n; ++j) {
            m[j * kHogProjectedDim + r] = static_cast<float>(normal.next() * scale);
          }
        }
      }
    }
  }

  const HogWindow& window(int view, int array) const noexcept {
    if (array == 1) return windows[1];
    return view == 2 ? windows[2] : windows[0];
  }

  // Canonical cloud (structure of arrays) and normalised intensity in [0.25, 1].
  std::vector<float> x, y, z, value;
  std::vector<std::int32_t> pixel;      // a point's pixel in the view being drawn, -1: cropped
                                        // (first its spin image bin)
  std::vector<std::int32_t> row_index;  // a point's row in the view being drawn
  std::vector<float> radius;            // a point's distance from the vertical axis
  std::uint32_t spin_count[4][kMaxSpinCells + 1]{};
  std::size_t n = 0;
  float yaw = 0.0f;
  // Views (0..255 scale, smoothed) and their sizes; accumulators shared between views.
  std::vector<float> images[kViews];
  int width[kViews] = {0, 0, 0}, height[kViews] = {0, 0, 0};
  std::vector<float> sum, count, smooth_tmp, raw_image;  // raw_image: before smoothing
  GradientCache gradients;
  HogWindow windows[3];                      // 15x30, 30x30, 15x15
  std::vector<float> projection[kViews][2];  // raw size x kHogProjectedDim (transposed)
  float raw[kMaxHogRaw]{};

  // The canonical axis a (0: x, 1: y, 2: z).
  [[nodiscard]] const float* axis(int a) const noexcept {
    return a == 0 ? x.data() : (a == 1 ? y.data() : z.data());
  }
  // The steps of compute() after canonicalize(), in order.
  // sp: spaces(), read once by compute().
  using Spaces = std::array<Space, kSpaceCount>;
  void box_size(const Spaces& sp, float (&lo)[3], float (&hi)[3], Descriptors& out) const noexcept;
  void spin_images(const Spaces& sp, Descriptors& out) noexcept;
  void view_and_hog(const Spaces& sp, int v, const float (&lo)[3], const float (&hi)[3],
                    const DescriptorConfig& config, Descriptors& out) noexcept;
  void place_windows(int v, ViewPlan& p) const noexcept;
  Rect keep_pixels(const ViewPlan& p, Descriptors& out) noexcept;
  void draw_view(int v, const ViewPlan& p, const Rect& occupied) noexcept;
  void hog_windows(const Spaces& sp, int v, const ViewPlan& p, const Rect& nonzero,
                   Descriptors& out) noexcept;
};

DescriptorPipeline::DescriptorPipeline(const DescriptorConfig& config) : config_(config) {
  if (const char* error = validate(config); error[0] != '\0') {
    throw std::invalid_argument(std::string("DescriptorConfig: ") + error);
  }
  (void)layout();
  state_ = std::make_unique<State>(config);
}

DescriptorPipeline::DescriptorPipeline(DescriptorPipeline&&) noexcept = default;
DescriptorPipeline& DescriptorPipeline::operator=(DescriptorPipeline&&) noexcept = default;
DescriptorPipeline::~DescriptorPipeline() = default;

DescriptorPipeline::Image DescriptorPipeline::image(View view) const noexcept {
  const int v = static_cast<int>(view);
  return {state_->images[v].data(), static_cast<std::size_t>(state_->width[v]),
          static_cast<std::size_t>(state_->height[v])};
}

float DescriptorPipeline::yaw() const noexcept {
  return state_->yaw;
}

namespace {

constexpr std::size_t kPrefetchAhead = 16;  // points

// Reads the segment's valid points (at most x.size(), evenly spaced) into x, y, z and value
// (intensity in [0.25, 1]); returns how many, with the sums of their x, y, z.
std::size_t read_points(const SegmentView& segment, const DescriptorConfig& config,
                        std::vector<float>& x, std::vector<float>& y, std::vector<float>& z,
                        std::vector<float>& value, double (&sums)[3], Descriptors& out) {
  std::size_t n = 0;
  const std::size_t total = segment.size();
  const double full = config.intensity_full_scale;
  // A segment of more than max_points is read at max_points evenly spaced positions.
  const std::size_t reads = std::min(total, x.size());
  out.points_over_capacity = static_cast<std::uint32_t>(total - reads);
  const auto position = [&](std::size_t j) {
    return reads == total ? j
                          : static_cast<std::size_t>(static_cast<std::uint64_t>(j) * total / reads);
  };
  double mx = 0, my = 0, mz = 0;
  for (std::size_t j = 0; j < reads; ++j) {
    // A segment's points are scattered over the scan (megabytes): each read is a cache miss
    // unless it is asked for well ahead.
    if (j + kPrefetchAhead < reads) segment.prefetch(position(j + kPrefetchAhead));
    float p[4];
    segment.read(position(j), p);
    if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2]) ||
        !std::isfinite(p[3])) {
      ++out.points_invalid;
      continue;
    }
    x[n] = p[0];
    y[n] = p[1];
    z[n] = p[2];
    const double i = std::clamp(static_cast<double>(p[3]) / full, 0.0, 1.0);
    value[n] = static_cast<float>(i * 0.75 + 0.25);
    mx += p[0];
    my += p[1];
    mz += p[2];
    ++n;
  }
  sums[0] = mx, sums[1] = my, sums[2] = mz;
  return n;
}

// Stage 1: read, drop invalid points, centre, rotate into the canonical frame.
void canonicalize(const SegmentView& segment, const DescriptorConfig& config, std::vector<float>& x,
                  std::vector<float>& y, std::vector<float>& z, std::vector<float>& value,
                  std::size_t& n, float& yaw, Descriptors& out) {
  double sums[3];
  n = read_points(segment, config, x, y, z, value, sums, out);
  if (n == 0) return;
  const double inv = 1.0 / static_cast<double>(n);
  const double mx = sums[0] * inv, my = sums[1] * inv, mz = sums[2] * inv;
  double sxx = 0, sxy = 0, syy = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const double dx = x[i] - mx, dy = y[i] - my;
    sxx += dx * dx;
    sxy += dx * dy;
    syy += dy * dy;
  }
  // Major axis of the XY covariance; its sign makes the third moment along it non-negative.
  double theta = 0.5 * std::atan2(2.0 * sxy, sxx - syy);
  double c = std::cos(theta), s = std::sin(theta), skew = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const double u = c * (x[i] - mx) + s * (y[i] - my);
    skew += u * u * u;
  }
  if (skew < 0) {
    theta += theta > 0 ? -M_PI : M_PI;
    c = -c;
    s = -s;
  }
  yaw = static_cast<float>(theta);
  for (std::size_t i = 0; i < n; ++i) {
    const double dx = x[i] - mx, dy = y[i] - my;
    x[i] = static_cast<float>(c * dx + s * dy);
    y[i] = static_cast<float>(-s * dx + c * dy);
    z[i] = static_cast<float>(z[i] - mz);
  }
}

// 3x3 Gaussian of OpenCV's cvSmooth(CV_GAUSSIAN, 3, 3): [1 2 1] / 4 separably, reflect-101 at
// the image's borders, from `src` to `img` within `out` only; it reads `src` within 1 px of
// `out`. The same sums as over the whole image.
void smooth3(const float* src, float* tmp, float* img, int w, int h, const Rect& out) noexcept {
  const int r0 = std::max(out.y0 - 1, 0), r1 = std::min(out.y1 + 1, h - 1);
  for (int r = r0; r <= r1; ++r) {  // the rows the column pass reads
    const float* in = src + static_cast<std::ptrdiff_t>(r) * w;
    float* o = tmp + static_cast<std::ptrdiff_t>(r) * w;
    auto at = [&](int c) {  // with the borders' reflections
      const float l = in[c > 0 ? c - 1 : (w > 1 ? 1 : 0)];
      const float rr = in[c + 1 < w ? c + 1 : (w > 1 ? w - 2 : 0)];
      o[c] = 0.25f * l + 0.5f * in[c] + 0.25f * rr;
    };
    // Columns 1 .. w-2 need no reflection: that loop does several at once.
    const int c0 = std::max(out.x0, 1), c1 = std::min(out.x1, w - 2);
    for (int c = out.x0; c <= out.x1 && c < c0; ++c) at(c);
    for (int c = c0; c <= c1; ++c) o[c] = 0.25f * in[c - 1] + 0.5f * in[c] + 0.25f * in[c + 1];
    for (int c = std::max(c1 + 1, c0); c <= out.x1; ++c) at(c);
  }
  for (int r = out.y0; r <= out.y1; ++r) {
    const int up = r > 0 ? r - 1 : (h > 1 ? 1 : 0);
    const int down = r + 1 < h ? r + 1 : (h > 1 ? h - 2 : 0);
    const float* a = tmp + static_cast<std::ptrdiff_t>(up) * w;
    const float* m = tmp + static_cast<std::ptrdiff_t>(r) * w;
    const float* b = tmp + static_cast<std::ptrdiff_t>(down) * w;
    float* o = img + static_cast<std::ptrdiff_t>(r) * w;
    for (int c = out.x0; c <= out.x1; ++c) o[c] = 0.25f * a[c] + 0.5f * m[c] + 0.25f * b[c];
  }
}

// Each point's bin in spin image `s` (row-major), or rows x cols (a bin that is dropped) when it
// falls outside; no branch, so several points at once.
void spin_bins(const float* __restrict radius, const float* __restrict z, std::size_t n,
               const SpinShape& s, float half, std::int32_t* __restrict bin) noexcept {
  const float ppm = s.px_per_m;
  // Unsigned: a negative index wraps to a large one, and the arithmetic of an index outside
  // is defined (and masked out).
  const auto rows = static_cast<std::uint32_t>(s.rows), cols = static_cast<std::uint32_t>(s.cols);
  const std::uint32_t dropped = rows * cols;
  for (std::size_t i = 0; i < n; ++i) {
    const auto col = static_cast<std::uint32_t>(floor_index(radius[i] * ppm));
    const auto row = static_cast<std::uint32_t>(floor_index((half - z[i]) * ppm));
    const std::uint32_t inside = 0u - static_cast<std::uint32_t>((col < cols) & (row < rows));
    bin[i] = static_cast<std::int32_t>(((row * cols + col) & inside) | (dropped & ~inside));
  }
}

// Each point's column and row in a view (floor of its scaled coordinates, as floor_index), no
// branch, so several points at once.
void view_cells(const float* __restrict us, const float* __restrict vs, std::size_t n, float ppm,
                float min_u, float pad_w, float max_v, float pad_h, std::int32_t* __restrict col,
                std::int32_t* __restrict row) noexcept {
  for (std::size_t i = 0; i < n; ++i) {
    col[i] = floor_index(us[i] * ppm - min_u + pad_w);
    row[i] = floor_index(max_v - vs[i] * ppm + pad_h);
  }
}

// out[c] = 255 sum[c] / count[c], or 0 without points, for c in [c0, c1); no branch (the
// division by 1 where count is 0 is discarded), so several pixels at once.
void mean_row(const float* __restrict sum, const float* __restrict count, int c0, int c1,
              float* __restrict out) noexcept {
  for (int c = c0; c < c1; ++c) {
    const float n = count[c];
    const float mean = 255.0f * sum[c] / (n > 0 ? n : 1.0f);
    out[c] = n > 0 ? mean : 0.0f;
  }
}

// A view's side from its extent (px): at least min_px (the points padded about the centre),
// at most cap (cropped about the centre, pad negative).
void fit_side(float extent, int min_px, int cap, int& size, float& pad) noexcept {
  size = static_cast<int>(std::ceil(extent)) + 1;
  pad = 0.0f;
  if (size < min_px) {
    pad = static_cast<float>(min_px - size) / 2.0f;
    size = min_px;
  } else if (size > cap) {
    pad = -static_cast<float>(size - cap) / 2.0f;  // crop about the centre
    size = cap;
  }
}

// The regions worked on: the offsets' distinct boxes, or their bounding box when that is
// no larger than they are together (small views, where the windows overlap).
void plan_regions(const Rect (&look)[4], ViewPlan& p) noexcept {
  Rect all{p.w, p.h, -1, -1};
  long separate = 0;
  p.regions = 0;
  for (int k = 0; k < 4; ++k) {
    int same = -1;
    for (int e = 0; e < p.regions && same < 0; ++e) {
      if (p.region[e] == look[k]) same = e;
    }
    if (same < 0) {
      same = p.regions;
      p.region[p.regions++] = look[k];
      separate += look[k].area();
    }
    p.region_of[k] = same;
    all = all.united(look[k]);
  }
  if (all.area() <= separate) {
    p.regions = 1;
    p.region[0] = all;
    for (int& r : p.region_of) r = 0;
  }
  for (int j = 0; j < p.regions; ++j) p.raw_rect[j] = p.region[j].grown(2, p.w, p.h);
}

// Zeroes buffer (w pixels a row) within q (which may be empty).
void zero_rect(std::vector<float>& buffer, const Rect& q, int w) noexcept {
  for (int r = q.y0; r <= q.y1 && q.x0 <= q.x1; ++r) {
    const std::ptrdiff_t a = static_cast<std::ptrdiff_t>(r) * w + q.x0;
    std::fill(buffer.begin() + a, buffer.begin() + a + (q.x1 - q.x0 + 1), 0.0f);
  }
}

// dst = M raw, each output summed over j in order (the same sums as row by row), the
// 20 outputs side by side so the compiler vectorises across them; empty bins skipped.
void project(const float* raw, std::size_t raw_n, const float* m, float* dst) noexcept {
  float acc[kHogProjectedDim] = {};
  for (std::size_t j = 0; j < raw_n; ++j) {
    const float r = raw[j];
    if (r == 0.0f) continue;
    const float* col = m + j * kHogProjectedDim;
    for (std::size_t k2 = 0; k2 < kHogProjectedDim; ++k2) acc[k2] += col[k2] * r;
  }
  std::copy(acc, acc + kHogProjectedDim, dst);
}

}  // namespace

// NOLINTNEXTLINE(bugprone-exception-escape): the layout exists already (see spaces())
void DescriptorPipeline::compute(const SegmentView& segment, Descriptors& out) noexcept {
  State& st = *state_;
  out.values.fill(0.0f);
  out.status = Status::kEmpty;
  out.points_used = out.points_invalid = out.points_over_capacity = out.pixels_cropped = 0;
  st.yaw = 0.0f;
  for (int v = 0; v < kViews; ++v) st.width[v] = st.height[v] = 0;
  canonicalize(segment, config_, st.x, st.y, st.z, st.value, st.n, st.yaw, out);
  out.points_used = static_cast<std::uint32_t>(st.n);
  if (st.n == 0) return;
  out.status = Status::kOk;
  float lo[3], hi[3];
  const auto& sp = spaces();
  st.box_size(sp, lo, hi, out);
  st.spin_images(sp, out);
  for (int v = 0; v < kViews; ++v) st.view_and_hog(sp, v, lo, hi, config_, out);
}

// (a) Oriented bounding box size (m): extents along canonical x, y, z.
void DescriptorPipeline::State::box_size(const Spaces& sp, float (&lo)[3], float (&hi)[3],
                                         Descriptors& out) const noexcept {
  for (int a = 0; a < 3; ++a) {
    const auto [mn, mx] = std::minmax_element(axis(a), axis(a) + n);
    lo[a] = *mn;
    hi[a] = *mx;
    out.values[sp[0].offset + static_cast<std::size_t>(a)] = hi[a] - lo[a];
  }
}

// (b) Spin images about the vertical axis through the centroid: column = floor(r * ppm),
// row = floor((rows / (2 ppm) - z) * ppm) (row 0 on top); counts, then whitened.
// Counted as integers (exact, as the float counts were: n < 2^24) in four interleaved copies,
// so that successive points in the same bin do not wait for each other; each point's bin is
// found first, in a loop without branches.
void DescriptorPipeline::State::spin_images(const Spaces& sp, Descriptors& out) noexcept {
  float* const r = radius.data();
  for (std::size_t i = 0; i < n; ++i) r[i] = std::sqrt(x[i] * x[i] + y[i] * y[i]);
  for (std::size_t k = 0; k < 4; ++k) {
    const SpinShape& s = kSpins[k];
    float* img = out.values.data() + sp[1 + k].offset;
    const float half = static_cast<float>(s.rows) / (2.0f * s.px_per_m);
    const int cells = s.rows * s.cols;
    std::int32_t* const bin = pixel.data();
    spin_bins(r, z.data(), n, s, half, bin);
    std::uint32_t(&counts)[4][kMaxSpinCells + 1] = spin_count;
    for (auto& c : counts) std::fill(c, c + cells + 1, 0u);
    std::size_t i = 0;
    for (; i + 4 <= n; i += 4) {
      ++counts[0][bin[i]];
      ++counts[1][bin[i + 1]];
      ++counts[2][bin[i + 2]];
      ++counts[3][bin[i + 3]];
    }
    for (; i < n; ++i) ++counts[0][bin[i]];
    for (int j = 0; j < cells; ++j) {
      img[j] = static_cast<float>(counts[0][j] + counts[1][j] + counts[2][j] + counts[3][j]);
    }
    whiten(img, sp[1 + k].size);
  }
}

// (c) Orthographic intensity image v, then (d) its HOG windows. View v drops canonical axis v;
// columns follow the first remaining axis, rows the second, top row = its maximum.
void DescriptorPipeline::State::view_and_hog(const Spaces& sp, int v, const float (&lo)[3],
                                             const float (&hi)[3], const DescriptorConfig& config,
                                             Descriptors& out) noexcept {
  const float ppm = static_cast<float>(config.image_px_per_m);
  constexpr int kAxes[kViews][2] = {{1, 2}, {0, 2}, {0, 1}};
  const float min_u = lo[kAxes[v][0]] * ppm, max_u = hi[kAxes[v][0]] * ppm;
  const float min_v = lo[kAxes[v][1]] * ppm, max_v = hi[kAxes[v][1]] * ppm;
  ViewPlan p;
  const int cap = static_cast<int>(config.max_image_px);
  const int min_px = static_cast<int>(config.min_image_px);
  fit_side(max_u - min_u, min_px, cap, p.w, p.pad_w);
  fit_side(max_v - min_v, min_px, cap, p.h, p.pad_h);
  width[v] = p.w;
  height[v] = p.h;
  place_windows(v, p);
  // Each point's pixel (-1: cropped, or too far from every window to matter), and the
  // rectangle the kept points cover: outside it (grown by the smoothing's and the gradient's
  // 1 px each) everything is exactly zero, so only that part is worked on.
  view_cells(axis(kAxes[v][0]), axis(kAxes[v][1]), n, ppm, min_u, p.pad_w, max_v, p.pad_h,
             pixel.data(), row_index.data());
  const Rect occupied = keep_pixels(p, out);
  if (!occupied.empty()) draw_view(v, p, occupied);
  // Where gradients may be non-zero (nowhere without a kept point).
  const Rect nonzero = occupied.empty() ? occupied : occupied.grown(2, p.w, p.h);
  hog_windows(sp, v, p, nonzero, out);
}

// Where the HOG windows go: centre (int(u W), int(v H)), shifted into the image. Only
// there are gradients needed, so the view is made only within 2 px of them (the gradient's
// and the smoothing's pixel); a large view is mostly outside every window.
void DescriptorPipeline::State::place_windows(int v, ViewPlan& p) const noexcept {
  const int w = p.w, h = p.h;
  Rect look[4];  // per offset: the bounding box of its two windows
  for (int k = 0; k < 4; ++k) {
    look[k] = Rect{w, h, -1, -1};
    for (int a = 0; a < 2; ++a) {
      const HogShape& shape = window(v, a).shape();
      const auto& o = kOffsets[k];
      const int x0 = std::clamp(static_cast<int>(o[0] * static_cast<float>(w)) - shape.width / 2, 0,
                                w - shape.width);
      const int y0 = std::clamp(static_cast<int>(o[1] * static_cast<float>(h)) - shape.height / 2,
                                0, h - shape.height);
      p.placed[a][k][0] = x0;
      p.placed[a][k][1] = y0;
      look[k] = look[k].united(Rect{x0, y0, x0 + shape.width - 1, y0 + shape.height - 1});
    }
  }
  plan_regions(look, p);
}

// Each point's pixel index (r * w + c) where a region reads it, else -1 (cropped ones counted);
// returns the rectangle the kept points cover.
Rect DescriptorPipeline::State::keep_pixels(const ViewPlan& p, Descriptors& out) noexcept {
  Rect occupied{p.w, p.h, -1, -1};
  for (std::size_t i = 0; i < n; ++i) {
    const int c = pixel[i], r = row_index[i];
    if (!(c >= 0 && c < p.w && r >= 0 && r < p.h)) {
      ++out.pixels_cropped;
      pixel[i] = -1;
      continue;
    }
    bool needed = false;
    for (int j = 0; j < p.regions && !needed; ++j) needed = p.raw_rect[j].contains(c, r);
    if (!needed) {
      pixel[i] = -1;
      continue;
    }
    pixel[i] = r * p.w + c;
    occupied = occupied.united(Rect{c, r, c, r});
  }
  return occupied;
}

// The view within each region: the mean intensity of each pixel's points (0 without points),
// then a 3x3 Gaussian. Only near the points is anything non-zero: the means within the
// occupied rectangle, the smoothed view within 1 px of it, the gradients within 2 px. Each
// buffer is zeroed where it is read but not computed, and the Gaussian reads `raw_image`,
// never written in place, so overlapping regions give the same values.
void DescriptorPipeline::State::draw_view(int v, const ViewPlan& p, const Rect& occupied) noexcept {
  const int w = p.w, h = p.h;
  Rect mean_rect[4], smooth_rect[4];
  for (int j = 0; j < p.regions; ++j) {
    mean_rect[j] = p.raw_rect[j].intersected(occupied);
    smooth_rect[j] = p.region[j].grown(1, w, h).intersected(occupied.grown(1, w, h));
    zero_rect(sum, mean_rect[j], w);
    zero_rect(count, mean_rect[j], w);
    zero_rect(raw_image, p.raw_rect[j].intersected(occupied.grown(2, w, h)), w);
    zero_rect(images[v], p.region[j].grown(1, w, h).intersected(occupied.grown(3, w, h)), w);
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (pixel[i] < 0) continue;
    const auto px = static_cast<std::size_t>(pixel[i]);
    sum[px] += value[i];
    count[px] += 1.0f;
  }
  for (int j = 0; j < p.regions; ++j) {
    const Rect& q = mean_rect[j];
    for (int r = q.y0; r <= q.y1; ++r) {
      const std::ptrdiff_t at = static_cast<std::ptrdiff_t>(r) * w;
      mean_row(sum.data() + at, count.data() + at, q.x0, q.x1 + 1, raw_image.data() + at);
    }
  }
  for (int j = 0; j < p.regions; ++j) {
    if (!smooth_rect[j].empty()) {
      smooth3(raw_image.data(), smooth_tmp.data(), images[v].data(), w, h, smooth_rect[j]);
    }
  }
}

// (d) HOG windows at the 4 offsets, each projected by its array's fixed random matrix.
void DescriptorPipeline::State::hog_windows(const Spaces& sp, int v, const ViewPlan& p,
                                            const Rect& nonzero, Descriptors& out) noexcept {
  const std::size_t space = 5 + 8 * static_cast<std::size_t>(v);
  int gradients_of = -1;  // the region whose gradients the cache holds
  for (int k = 0; k < 4; ++k) {
    for (int a = 0; a < 2; ++a) {
      const HogWindow& win = window(v, a);
      const int x0 = p.placed[a][k][0], y0 = p.placed[a][k][1];
      const std::size_t slot = space + static_cast<std::size_t>(a * 4 + k);
      float* dst = out.values.data() + sp[slot].offset;
      int same = -1;  // an earlier offset of this array landed on the same window: reuse it
      for (int e = 0; e < k && same < 0; ++e) {
        if (p.placed[a][e][0] == x0 && p.placed[a][e][1] == y0) same = e;
      }
      if (same >= 0) {
        const float* src = out.values.data() + sp[slot - static_cast<std::size_t>(k - same)].offset;
        std::copy(src, src + kHogProjectedDim, dst);
        continue;
      }
      if (gradients_of != p.region_of[k]) {
        gradients_of = p.region_of[k];
        const Rect g = p.region[gradients_of].intersected(nonzero);
        gradients.reset(images[v].data(), p.w, p.h, g.x0, g.y0, g.x1 + 1, g.y1 + 1);
      }
      win.compute(gradients, x0, y0, raw);
      project(raw, win.shape().size(), projection[v][a].data(), dst);
    }
  }
}

}  // namespace stac::descriptors
