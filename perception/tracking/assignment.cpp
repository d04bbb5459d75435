#include "perception/tracking/assignment.hpp"

#include <algorithm>
#include <limits>

namespace stac::tracking {

AssignmentSolver::AssignmentSolver(std::size_t max_rows, std::size_t max_cols)
    : max_rows_(max_rows), max_cols_(max_cols) {
  const std::size_t big = std::max(max_rows, max_cols) + 1;
  u_.assign(big, 0.0);
  v_.assign(big, 0.0);
  minv_.assign(big, 0.0);
  p_.assign(big, 0);
  way_.assign(big, 0);
  used_.assign(big, 0);
}

bool AssignmentSolver::solve(std::span<const double> cost, std::size_t rows, std::size_t cols,
                             std::span<int> row_to_col) noexcept {
  const bool fits =
      (rows <= max_rows_ && cols <= max_cols_) || (rows <= max_cols_ && cols <= max_rows_);
  if (!fits || row_to_col.size() < rows || cost.size() < rows * cols) return false;
  for (std::size_t i = 0; i < rows; ++i) row_to_col[i] = -1;
  if (rows == 0 || cols == 0) return true;

  // The algorithm needs n <= m: work on the transpose when there are more rows than columns.
  const bool transposed = rows > cols;
  const std::size_t n = transposed ? cols : rows;
  const std::size_t m = transposed ? rows : cols;
  auto a = [&](std::size_t i, std::size_t j) {  // 1-based
    return transposed ? cost[(j - 1) * cols + (i - 1)] : cost[(i - 1) * cols + (j - 1)];
  };
  constexpr double kInf = std::numeric_limits<double>::infinity();
  std::fill_n(u_.begin(), n + 1, 0.0);
  std::fill_n(v_.begin(), m + 1, 0.0);
  std::fill_n(p_.begin(), m + 1, 0);
  std::fill_n(way_.begin(), m + 1, 0);

  for (std::size_t i = 1; i <= n; ++i) {
    p_[0] = static_cast<int>(i);
    std::size_t j0 = 0;
    std::fill_n(minv_.begin(), m + 1, kInf);
    std::fill_n(used_.begin(), m + 1, 0);
    do {
      used_[j0] = 1;
      const auto i0 = static_cast<std::size_t>(p_[j0]);
      double delta = kInf;
      std::size_t j1 = 0;
      for (std::size_t j = 1; j <= m; ++j) {
        if (used_[j]) continue;
        const double cur = a(i0, j) - u_[i0] - v_[j];
        if (cur < minv_[j]) {
          minv_[j] = cur;
          way_[j] = static_cast<int>(j0);
        }
        if (minv_[j] < delta) {
          delta = minv_[j];
          j1 = j;
        }
      }
      if (j1 == 0) return false;  // non-finite costs: refuse rather than loop forever
      for (std::size_t j = 0; j <= m; ++j) {
        if (used_[j]) {
          u_[static_cast<std::size_t>(p_[j])] += delta;
          v_[j] -= delta;
        } else {
          minv_[j] -= delta;
        }
      }
      j0 = j1;
    } while (p_[j0] != 0);
    do {
      const auto j1 = static_cast<std::size_t>(way_[j0]);
      p_[j0] = p_[j1];
      j0 = j1;
    } while (j0 != 0);
  }

  for (std::size_t j = 1; j <= m; ++j) {
    if (p_[j] == 0) continue;
    const auto i = static_cast<std::size_t>(p_[j]) - 1;  // 0-based row of the n side
    if (transposed) {
      row_to_col[j - 1] = static_cast<int>(i);
    } else {
      row_to_col[i] = static_cast<int>(j - 1);
    }
  }
  return true;
}

}  // namespace stac::tracking
