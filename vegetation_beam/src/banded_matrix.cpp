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
  inverse_pivot_.resize(n);
  for (int k = 0; k < n; ++k) {
    const double pivot = at(k, k);
    if (pivot == 0.0 || !std::isfinite(pivot)) {
      if (failed_row != nullptr) *failed_row = k;
      return false;
    }
    inverse_pivot_[k] = 1.0 / pivot;
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

namespace {

// Forward and back substitution with the factors stored row by row, `width` entries a row with
// the diagonal at offset w. Both go by columns: once x_k is known, it is taken out of the w rows
// it couples, which are independent of each other, so a row waits for one multiply-subtract per
// column instead of a chain of w (and the pivots are multiplied by their stored inverses, not
// divided by). With w known at compile time (Fixed > 0) the loops over a full band unroll; the
// operations and their order are the same either way.
template <int Fixed>
void substitute(const double* data, const double* inverse_pivot, int n, int runtime_w, int width,
                double* rhs) {
  const int w = Fixed > 0 ? Fixed : runtime_w;
  for (int k = 0; k < n; ++k) {
    const double rk = rhs[k];
    if (Fixed > 0 && k + w < n) {
      for (int i = 1; i <= Fixed; ++i) rhs[k + i] -= data[(k + i) * width + (w - i)] * rk;
    } else {
      const int last = std::min(n - 1, k + w);
      for (int i = k + 1; i <= last; ++i) rhs[i] -= data[i * width + (k - i + w)] * rk;
    }
  }
  for (int k = n - 1; k >= 0; --k) {
    const double xk = rhs[k] * inverse_pivot[k];
    rhs[k] = xk;
    // U(i, k) = data[i * width + (k - i + w)] for the rows i = k - w .. k - 1 above.
    if (Fixed > 0 && k >= w) {
      for (int i = 1; i <= Fixed; ++i) rhs[k - i] -= data[(k - i) * width + (w + i)] * xk;
    } else {
      for (int i = std::max(0, k - w); i < k; ++i) rhs[i] -= data[i * width + (k - i + w)] * xk;
    }
  }
}

}  // namespace

void BandedMatrix::solve(std::vector<double>& rhs) const {
  if (half_bandwidth_ == 8) {  // the plants' Jacobian: 3 dofs a node, bending two nodes apart
    substitute<8>(data_.data(), inverse_pivot_.data(), size_, half_bandwidth_, width_, rhs.data());
  } else {
    substitute<0>(data_.data(), inverse_pivot_.data(), size_, half_bandwidth_, width_, rhs.data());
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
