// Square band matrix with LU solve without pivoting: the Newmark Jacobian of one plant couples a
// node only with its two neighbours on either side (bending joints), so 3 dofs per node give a
// half bandwidth of 8. The mass term M / (beta dt^2) makes the matrix diagonally dominant at the
// sub-steps used, which is why pivoting is not needed.
#pragma once

#include <Eigen/Core>
#include <vector>

namespace cosim::vegetation {

class BandedMatrix {
 public:
  void resize(int size, int half_bandwidth);
  void set_zero();
  int size() const { return size_; }
  int half_bandwidth() const { return half_bandwidth_; }

  double& at(int row, int col) { return data_[index(row, col)]; }
  double at(int row, int col) const { return data_[index(row, col)]; }
  // Adds weight * block at the 3x3 block of node rows `row_node`, node columns `col_node`.
  void add_block(int row_node, int col_node, const Eigen::Matrix3d& block, double weight);
  // Adds stiffness_weight * stiffness, then damping_weight * damping, entry by entry (the sums
  // of two add_block calls, in one pass).
  void add_blocks(int row_node, int col_node, const Eigen::Matrix3d& stiffness,
                  double stiffness_weight, const Eigen::Matrix3d& damping, double damping_weight) {
    for (int r = 0; r < 3; ++r) {
      double* row = &at(3 * row_node + r, 3 * col_node);
      for (int c = 0; c < 3; ++c) {
        row[c] += stiffness_weight * stiffness(r, c);
        row[c] += damping_weight * damping(r, c);
      }
    }
  }
  void add_diagonal(int row, double value) { at(row, row) += value; }

  // LU factorisation in place; false on a zero or non-finite pivot, whose row goes into
  // `failed_row` when given.
  bool factorize(int* failed_row = nullptr);
  // Solves with the factors of factorize(), overwriting rhs with the solution.
  void solve(std::vector<double>& rhs) const;
  bool solve_in_place(std::vector<double>& rhs) {
    if (!factorize()) return false;
    solve(rhs);
    return true;
  }

  Eigen::MatrixXd to_dense() const;

 private:
  int index(int row, int col) const { return row * width_ + (col - row + half_bandwidth_); }
  int size_ = 0, half_bandwidth_ = 0, width_ = 1;
  std::vector<double> data_;
  std::vector<double> inverse_pivot_;  // 1 / U(k, k), set by factorize()
};

}  // namespace cosim::vegetation
