// Box fit (docs/segmentation.md): per kept segment its centroid, height span and oriented box,
// the heading from the XY principal axis or, for long segments, L-shape fitting's rectangle
// search.
#include <algorithm>
#include <cmath>
#include <limits>
#include <span>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "perception/segmentation/segmenter_state.hpp"

namespace stac::segmentation {
namespace {

constexpr float kMinDistance = 0.01f;  // closeness: the nearest an edge counts (m)

// Up to `cap` of the points (evenly strided) about (mx, my) into fx, fy; returns how many.
std::size_t sample_about(const PointView& points, std::span<const std::uint32_t> indices, double mx,
                         double my, float* fx, float* fy, std::size_t cap) noexcept {
  const std::size_t n = indices.size();
  const std::size_t stride = (n + cap - 1) / cap;
  std::size_t m = 0;
  for (std::size_t k = 0; k < n && m < cap; k += stride) {
    float x, y, z;
    points.read(indices[k], x, y, z);
    fx[m] = static_cast<float>(x - mx);
    fy[m] = static_cast<float>(y - my);
    ++m;
  }
#if defined(__SSE2__)
  // Pads to a multiple of four with copies of the first point: no change to the rectangle;
  // their terms are masked out of the sum.
  const std::size_t m4 = (m + 3) / 4 * 4;
  for (std::size_t i = m; i < m4; ++i) fx[i] = fx[0], fy[i] = fy[0];
#endif
  return m;
}

// The score of one heading, four points at a time where SSE is there (the x86-64 baseline):
// the same rectangle, the sum in another order (four partial sums).
#if defined(__SSE2__)
// Across the lanes.
template <typename Op>
__m128 reduce(__m128 a, Op op) noexcept {
  a = op(a, _mm_shuffle_ps(a, a, _MM_SHUFFLE(1, 0, 3, 2)));
  return op(a, _mm_shuffle_ps(a, a, _MM_SHUFFLE(2, 3, 0, 1)));
}

float closeness(const float* fx, const float* fy, std::size_t m, double yaw) noexcept {
  const std::size_t m4 = (m + 3) / 4 * 4;
  const auto ca = static_cast<float>(std::cos(yaw)), sa = static_cast<float>(std::sin(yaw));
  const __m128 c = _mm_set1_ps(ca), sn = _mm_set1_ps(sa), ns = _mm_set1_ps(-sa);
  __m128 u0 = _mm_set1_ps(std::numeric_limits<float>::infinity());
  __m128 u1 = _mm_set1_ps(-std::numeric_limits<float>::infinity()), v0 = u0, v1 = u1;
  for (std::size_t i = 0; i < m4; i += 4) {
    const __m128 x = _mm_loadu_ps(fx + i), y = _mm_loadu_ps(fy + i);
    const __m128 u = _mm_add_ps(_mm_mul_ps(c, x), _mm_mul_ps(sn, y));
    const __m128 v = _mm_add_ps(_mm_mul_ps(ns, x), _mm_mul_ps(c, y));
    u0 = _mm_min_ps(u0, u), u1 = _mm_max_ps(u1, u), v0 = _mm_min_ps(v0, v), v1 = _mm_max_ps(v1, v);
  }
  const auto min = [](__m128 a, __m128 b) { return _mm_min_ps(a, b); };
  const auto max = [](__m128 a, __m128 b) { return _mm_max_ps(a, b); };
  u0 = reduce(u0, min), u1 = reduce(u1, max), v0 = reduce(v0, min), v1 = reduce(v1, max);
  const __m128 floor = _mm_set1_ps(kMinDistance), one = _mm_set1_ps(1.0f);
  __m128 sum = _mm_setzero_ps();
  for (std::size_t i = 0; i < m4; i += 4) {
    const __m128 x = _mm_loadu_ps(fx + i), y = _mm_loadu_ps(fy + i);
    const __m128 u = _mm_add_ps(_mm_mul_ps(c, x), _mm_mul_ps(sn, y));
    const __m128 v = _mm_add_ps(_mm_mul_ps(ns, x), _mm_mul_ps(c, y));
    const __m128 d = _mm_min_ps(_mm_min_ps(_mm_sub_ps(u, u0), _mm_sub_ps(u1, u)),
                                _mm_min_ps(_mm_sub_ps(v, v0), _mm_sub_ps(v1, v)));
    __m128 term = _mm_div_ps(one, _mm_max_ps(d, floor));
    if (i + 4 > m) {  // the padded lanes of the last four
      alignas(16) float keep[4];
      for (std::size_t l = 0; l < 4; ++l) keep[l] = i + l < m ? 1.0f : 0.0f;
      term = _mm_mul_ps(term, _mm_load_ps(keep));
    }
    sum = _mm_add_ps(sum, term);
  }
  sum = reduce(sum, [](__m128 a, __m128 b) { return _mm_add_ps(a, b); });
  return _mm_cvtss_f32(sum);
}
#else
float closeness(const float* fx, const float* fy, std::size_t m, double yaw) noexcept {
  const auto ca = static_cast<float>(std::cos(yaw)), sa = static_cast<float>(std::sin(yaw));
  float u0 = std::numeric_limits<float>::infinity(), u1 = -u0, v0 = u0, v1 = -u0;
  for (std::size_t i = 0; i < m; ++i) {
    const float u = ca * fx[i] + sa * fy[i], v = -sa * fx[i] + ca * fy[i];
    u0 = std::min(u0, u), u1 = std::max(u1, u), v0 = std::min(v0, v), v1 = std::max(v1, v);
  }
  float score = 0;
  for (std::size_t i = 0; i < m; ++i) {
    const float u = ca * fx[i] + sa * fy[i], v = -sa * fx[i] + ca * fy[i];
    const float d = std::min(std::min(u - u0, u1 - u), std::min(v - v0, v1 - v));
    score += 1.0f / std::max(d, kMinDistance);
  }
  return score;
}
#endif

// L-shape fitting's rectangle search (SegmenterConfig::box_fit_points): the heading in
// [-5, 95) degrees whose rectangle the points lie closest to the edges of, by the closeness
// criterion (sum over the points of 1 / max(distance to the nearer edge, 1 cm)), searched every
// 6 degrees and then every degree within 5 of the best, over up to `cap` of the points (evenly
// strided) about (mx, my).
double fit_heading(const PointView& points, std::span<const std::uint32_t> indices, double mx,
                   double my, float* fx, float* fy, std::size_t cap) noexcept {
  const std::size_t m = sample_about(points, indices, mx, my, fx, fy, cap);
  // Every 6 degrees, then every degree within 5 of the best.
  constexpr double kDegree = M_PI / 180;
  int best_step = 0;
  float best = -1;
  for (int a = 0; a < 90; a += 6) {
    const float score = closeness(fx, fy, m, a * kDegree);
    if (score > best) best = score, best_step = a;
  }
  const int coarse = best_step;
  for (int a = coarse - 5; a <= coarse + 5; ++a) {
    if (a == coarse) continue;
    const float score = closeness(fx, fy, m, a * kDegree);
    if (score > best) best = score, best_step = a;
  }
  return best_step * kDegree;
}

// The extents of the points along yaw and across it, about (mx, my).
struct Extents {
  double ca = 0, sa = 0, u0 = 0, u1 = 0, v0 = 0, v1 = 0;
};

Extents extents(const PointView& points, std::span<const std::uint32_t> indices, double mx,
                double my, double yaw) noexcept {
  Extents e;
  e.ca = std::cos(yaw), e.sa = std::sin(yaw);
  e.u0 = std::numeric_limits<double>::infinity(), e.u1 = -e.u0, e.v0 = e.u0, e.v1 = -e.u0;
  for (const std::uint32_t i : indices) {
    float x, y, z;
    points.read(i, x, y, z);
    const double dx = x - mx, dy = y - my;
    const double u = e.ca * dx + e.sa * dy, v = -e.sa * dx + e.ca * dy;
    e.u0 = std::min(e.u0, u), e.u1 = std::max(e.u1, u), e.v0 = std::min(e.v0, v),
    e.v1 = std::max(e.v1, v);
  }
  return e;
}

// A segment's box from its centroid (mx, my), the extents along its heading and its heights.
OrientedBox box_of(double mx, double my, const Extents& e, double yaw, float zlo,
                   float zhi) noexcept {
  const double uc = 0.5 * (e.u0 + e.u1), vc = 0.5 * (e.v0 + e.v1);
  OrientedBox b;
  b.cx = static_cast<float>(mx + e.ca * uc - e.sa * vc);
  b.cy = static_cast<float>(my + e.sa * uc + e.ca * vc);
  b.cz = 0.5f * (zlo + zhi);
  b.length = static_cast<float>(e.u1 - e.u0);
  b.width = static_cast<float>(e.v1 - e.v0);
  b.height = zhi - zlo;
  double box_yaw = yaw;
  if (b.width > b.length) {
    std::swap(b.length, b.width);
    box_yaw += box_yaw > 0 ? -M_PI / 2 : M_PI / 2;
  }
  b.yaw = static_cast<float>(box_yaw);
  return b;
}

// Per segment: centroid, height span, oriented box from the XY principal axis (or the
// rectangle fit, for long segments).
void describe_segment(const PointView& points, std::span<const std::uint32_t> indices,
                      const SegmenterConfig& c, float* fit_x, float* fit_y, Segment& seg) noexcept {
  // Sums relative to the first point keep the second moments well conditioned.
  float x0, y0, z0;
  points.read(indices[0], x0, y0, z0);
  double sx = 0, sy = 0, sz = 0, sxx = 0, sxy = 0, syy = 0;
  float zlo = z0, zhi = z0;
  for (const std::uint32_t i : indices) {
    float x, y, z;
    points.read(i, x, y, z);
    const double dx = x - x0, dy = y - y0;
    sx += dx, sy += dy, sz += z;
    sxx += dx * dx, sxy += dx * dy, syy += dy * dy;
    zlo = std::min(zlo, z), zhi = std::max(zhi, z);
  }
  const double inv = 1.0 / seg.count;
  const double mx = x0 + sx * inv, my = y0 + sy * inv;
  const double cxx = sxx * inv - sx * sx * inv * inv, cxy = sxy * inv - sx * sy * inv * inv,
               cyy = syy * inv - sy * sy * inv * inv;
  double yaw = 0.5 * std::atan2(2.0 * cxy, cxx - cyy);
  Extents e = extents(points, indices, mx, my, yaw);
  if (c.box_fit_points > 0 && std::max(e.u1 - e.u0, e.v1 - e.v0) >= c.box_fit_min_length_m) {
    yaw = fit_heading(points, indices, mx, my, fit_x, fit_y, c.box_fit_points);
    e = extents(points, indices, mx, my, yaw);
  }
  seg.centroid[0] = static_cast<float>(mx);
  seg.centroid[1] = static_cast<float>(my);
  seg.centroid[2] = static_cast<float>(sz * inv);
  seg.z_min = zlo;
  seg.z_max = zhi;
  seg.box = box_of(mx, my, e, yaw, zlo, zhi);
}

}  // namespace

void Segmenter::State::describe(const PointView& points, const SegmenterConfig& c,
                                Segments& out) noexcept {
  for (Segment& seg : out.segments) {
    describe_segment(points, out.indices(seg), c, fit_x.data(), fit_y.data(), seg);
  }
}

}  // namespace stac::segmentation
