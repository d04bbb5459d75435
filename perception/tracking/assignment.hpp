// Minimum-cost rectangular assignment (Hungarian method with potentials, O(n^2 m)), solved on
// workspace allocated once at construction: solve() never allocates.
#pragma once

#include <cstddef>
#include <span>
#include <vector>

namespace stac::tracking {

class AssignmentSolver {
 public:
  // Capacity: the largest matrix solve() accepts (rows x cols, either orientation).
  AssignmentSolver(std::size_t max_rows, std::size_t max_cols);

  // cost: row-major rows x cols, finite values (callers encode "forbidden" as a large finite
  // cost and drop such pairs afterwards). Fills row_to_col[i] with the column of row i, or -1
  // when rows > cols leaves row i unassigned. Every row (rows <= cols) or every column
  // (rows > cols) is assigned, minimising the total cost.
  // Returns false when the matrix exceeds the capacity, row_to_col.size() < rows or a cost is
  // not finite (row_to_col is then meaningless).
  [[nodiscard]] bool solve(std::span<const double> cost, std::size_t rows, std::size_t cols,
                           std::span<int> row_to_col) noexcept;

 private:
  std::size_t max_rows_, max_cols_;
  // Indexed 0..n or 0..m (1-based algorithm, slot 0 is the virtual start).
  std::vector<double> u_, v_, minv_;
  std::vector<int> p_, way_;
  std::vector<unsigned char> used_;
};

}  // namespace stac::tracking
