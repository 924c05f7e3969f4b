#include "cosim/vegetation_beam/banded_matrix.hpp"

#include <algorithm>
#include <cmath>

namespace cosim::vegetation {

void BandedMatrix::resize(int size, int half_bandwidth) {
  size_ = size;
  half_bandwidth_ = half_bandwidth;
  width_ = 2 * half_bandwidth + 1;
  data_.assign(static_cast<std::size_t>(size_) * width_, 0.0);
}

void BandedMatrix::set_zero() {
  std::fill(data_.begin(), data_.end(), 0.0);
}

void BandedMatrix::add_block(int row_node, int col_node, const Eigen::Matrix3d& block,
                             double weight) {
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) {
      at(3 * row_node + r, 3 * col_node + c) += weight * block(r, c);
    }
  }
}

bool BandedMatrix::factorize(int* failed_row) {
  const int n = size_, w = half_bandwidth_;
  // Gaussian elimination restricted to the band (no fill-in outside it without pivoting); the
  // multipliers are kept below the diagonal.
  for (int k = 0; k < n; ++k) {
    const double pivot = at(k, k);
    if (pivot == 0.0 || !std::isfinite(pivot)) {
      if (failed_row != nullptr) *failed_row = k;
      return false;
    }
    const int last = std::min(n - 1, k + w);
    for (int i = k + 1; i <= last; ++i) {
      const double factor = at(i, k) / pivot;
      at(i, k) = factor;
      if (factor == 0.0) continue;
      for (int j = k + 1; j <= last; ++j) at(i, j) -= factor * at(k, j);
    }
  }
  return true;
}

void BandedMatrix::solve(std::vector<double>& rhs) const {
  const int n = size_, w = half_bandwidth_;
  for (int k = 0; k < n; ++k) {
    const int last = std::min(n - 1, k + w);
    for (int i = k + 1; i <= last; ++i) rhs[i] -= at(i, k) * rhs[k];
  }
  for (int k = n - 1; k >= 0; --k) {
    double sum = rhs[k];
    const int last = std::min(n - 1, k + w);
    for (int j = k + 1; j <= last; ++j) sum -= at(k, j) * rhs[j];
    rhs[k] = sum / at(k, k);
  }
}

Eigen::MatrixXd BandedMatrix::to_dense() const {
  Eigen::MatrixXd dense = Eigen::MatrixXd::Zero(size_, size_);
  for (int i = 0; i < size_; ++i) {
    const int first = std::max(0, i - half_bandwidth_);
    const int last = std::min(size_ - 1, i + half_bandwidth_);
    for (int j = first; j <= last; ++j) dense(i, j) = at(i, j);
  }
  return dense;
}

}  // namespace cosim::vegetation
