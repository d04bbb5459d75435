#include "perception/tracking/assignment.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>
#include <vector>

namespace stac::tracking {
namespace {

double total(const std::vector<double>& cost, std::size_t cols,
             const std::vector<int>& row_to_col) {
  double sum = 0;
  for (std::size_t i = 0; i < row_to_col.size(); ++i) {
    if (row_to_col[i] >= 0) sum += cost[i * cols + static_cast<std::size_t>(row_to_col[i])];
  }
  return sum;
}

// Every assignment of min(rows, cols) pairs, by permutation of the larger side.
double brute_force(const std::vector<double>& cost, std::size_t rows, std::size_t cols) {
  const std::size_t big = std::max(rows, cols);
  std::vector<std::size_t> perm(big);
  std::iota(perm.begin(), perm.end(), 0);
  double best = std::numeric_limits<double>::infinity();
  do {
    double sum = 0;
    if (rows <= cols) {
      for (std::size_t i = 0; i < rows; ++i) sum += cost[i * cols + perm[i]];
    } else {
      for (std::size_t j = 0; j < cols; ++j) sum += cost[perm[j] * cols + j];
    }
    best = std::min(best, sum);
  } while (std::next_permutation(perm.begin(), perm.end()));
  return best;
}

TEST(AssignmentSolver, MatchesBruteForceOnRandomSmallMatrices) {
  std::mt19937 rng(12345);
  std::uniform_real_distribution<double> value(0.0, 10.0);
  std::uniform_int_distribution<std::size_t> size(1, 6);
  AssignmentSolver solver(6, 6);
  for (int trial = 0; trial < 500; ++trial) {
    const std::size_t rows = size(rng), cols = size(rng);
    std::vector<double> cost(rows * cols);
    // Some integer matrices, to exercise ties.
    for (double& c : cost) c = trial % 3 == 0 ? std::floor(value(rng) / 3) : value(rng);
    std::vector<int> row_to_col(rows, -7);
    ASSERT_TRUE(solver.solve(cost, rows, cols, row_to_col));
    // A valid assignment: min(rows, cols) pairs, no column used twice.
    std::vector<int> used(cols, 0);
    std::size_t pairs = 0;
    for (const int c : row_to_col) {
      if (c < 0) continue;
      ASSERT_LT(c, static_cast<int>(cols));
      EXPECT_EQ(used[static_cast<std::size_t>(c)]++, 0);
      ++pairs;
    }
    EXPECT_EQ(pairs, std::min(rows, cols));
    EXPECT_NEAR(total(cost, cols, row_to_col), brute_force(cost, rows, cols), 1e-9)
        << rows << "x" << cols << " trial " << trial;
  }
}

// A greedy matcher (cheapest pair first), the thing global assignment must beat.
std::vector<int> greedy(const std::vector<double>& cost, std::size_t rows, std::size_t cols) {
  std::vector<int> out(rows, -1);
  std::vector<bool> col_used(cols, false);
  for (std::size_t k = 0; k < std::min(rows, cols); ++k) {
    double best = std::numeric_limits<double>::infinity();
    std::size_t bi = 0, bj = 0;
    for (std::size_t i = 0; i < rows; ++i) {
      for (std::size_t j = 0; j < cols; ++j) {
        if (out[i] < 0 && !col_used[j] && cost[i * cols + j] < best) {
          best = cost[i * cols + j];
          bi = i;
          bj = j;
        }
      }
    }
    out[bi] = static_cast<int>(bj);
    col_used[bj] = true;
  }
  return out;
}

TEST(AssignmentSolver, BeatsGreedyWhereTheCheapestPairIsWrong) {
  // Row 0 is closest to column 0, but taking that pair forces row 1 onto column 1 at a high cost.
  const std::vector<double> cost = {1.0, 2.0, 2.0, 10.0};
  AssignmentSolver solver(2, 2);
  std::vector<int> global(2);
  ASSERT_TRUE(solver.solve(cost, 2, 2, global));
  EXPECT_EQ(greedy(cost, 2, 2), (std::vector<int>{0, 1}));
  EXPECT_EQ(global, (std::vector<int>{1, 0}));
  EXPECT_DOUBLE_EQ(total(cost, 2, global), 4.0);
}

TEST(AssignmentSolver, RefusesOversizedOrNonFiniteInputWithoutHanging) {
  AssignmentSolver solver(2, 3);
  std::vector<int> out(4);
  const std::vector<double> big(16, 1.0);
  EXPECT_FALSE(solver.solve(big, 4, 4, out));
  EXPECT_TRUE(solver.solve(big, 3, 2, out));  // the transpose fits
  const double inf = std::numeric_limits<double>::infinity();
  const std::vector<double> bad = {inf, inf, inf, inf};
  EXPECT_FALSE(solver.solve(bad, 2, 2, out));
  std::vector<int> small(1);
  EXPECT_FALSE(solver.solve(big, 2, 2, small));  // output too short
}

TEST(AssignmentSolver, EmptyMatrixAssignsNothing) {
  AssignmentSolver solver(4, 4);
  std::vector<int> out(3, 5);
  EXPECT_TRUE(solver.solve({}, 3, 0, out));
  EXPECT_EQ(out, (std::vector<int>{-1, -1, -1}));
}

}  // namespace
}  // namespace stac::tracking
