#include "upper_triangle.hpp"

#include <algorithm>

namespace cosim::mps {
namespace {

int block_of(int row) {
  return row / UpperTriangle::kBlock;
}

// Where the entry (row, column) of a row goes (see UpperTriangle): the diagonal; a near pair,
// kept once in its upper row; a far pair, kept in both rows; or nowhere (a near pair's lower
// entry).
enum class Entry { diagonal, near, far, lower_near };

Entry entry_kind(int row, int column) {
  if (column == row) return Entry::diagonal;
  const int upper = std::max(row, column), lower = std::min(row, column);
  if (block_of(upper) - block_of(lower) > UpperTriangle::kNearBlocks) return Entry::far;
  return column > row ? Entry::near : Entry::lower_near;
}

}  // namespace

void UpperTriangle::build(const SparseRows& m, bool single_value) {
  const int n = m.rows();
  rows_ = n;
  single_ = single_value;
  const int blocks = (n + kBlock - 1) / kBlock;
  diagonal_.resize(n);
  near_offset_.assign(static_cast<std::size_t>(n) + 1, 0);
  far_offset_.assign(static_cast<std::size_t>(n) + 1, 0);
  window_end_.resize(blocks);
#pragma omp parallel for schedule(static) if (blocks >= 4)
  for (int block = 0; block < blocks; ++block) {
    const int begin = block * kBlock, end = std::min(n, begin + kBlock);
    int window_end = end;
    for (int i = begin; i < end; ++i) {
      std::int64_t near = 0, far = 0;
      for (std::int64_t k = m.offset[i]; k < m.offset[i + 1]; ++k) {
        const int j = m.column[k];  // only the columns are read here
        const Entry kind = entry_kind(i, j);
        if (kind == Entry::near) {
          ++near;
          window_end = std::max(window_end, j + 1);
        } else if (kind == Entry::far) {
          ++far;
        }
      }
      near_offset_[i + 1] = near;
      far_offset_[i + 1] = far;
    }
    window_end_[block] = window_end;
  }
  for (int i = 0; i < n; ++i) {
    near_offset_[i + 1] += near_offset_[i];
    far_offset_[i + 1] += far_offset_[i];
  }
  window_start_.resize(static_cast<std::size_t>(blocks) + 1);
  window_start_[0] = 0;
  for (int block = 0; block < blocks; ++block) {
    window_start_[block + 1] = window_start_[block] + (window_end_[block] - block * kBlock);
  }
  window_.resize(window_start_[blocks]);
  near_column_.resize(near_offset_[n]);
  far_column_.resize(far_offset_[n]);
  fill(m);
  if (!single_) return;
  // The float copies the iterations read; the double values stay for the true residuals.
  near_single_.resize(near_value_.size());
  far_single_.resize(far_value_.size());
  const std::int64_t near = near_offset_[n], far = far_offset_[n];
#pragma omp parallel for schedule(static) if (near >= 65536)
  for (std::int64_t k = 0; k < near; ++k) near_single_[k] = static_cast<float>(near_value_[k]);
  for (std::int64_t k = 0; k < far; ++k) far_single_[k] = static_cast<float>(far_value_[k]);
}

void UpperTriangle::fill(const SparseRows& m) {
  const int n = rows_;
  near_value_.resize(near_offset_[n]);
  far_value_.resize(far_offset_[n]);
  double* near_value = near_value_.data();
  double* far_value = far_value_.data();
#pragma omp parallel for schedule(static) if (n >= 4096)
  for (int i = 0; i < n; ++i) {
    const int first = block_of(i) * kBlock;
    std::int64_t near = near_offset_[i], far = far_offset_[i];
    double diagonal = 0.0;
    for (std::int64_t k = m.offset[i]; k < m.offset[i + 1]; ++k) {
      const int j = m.column[k];
      const double v = m.value[k];
      switch (entry_kind(i, j)) {
        case Entry::diagonal:
          diagonal += v;
          break;
        case Entry::near:
          near_column_[near] = static_cast<std::uint16_t>(j - first);
          near_value[near++] = v;
          break;
        case Entry::far:
          far_column_[far] = j;
          far_value[far++] = v;
          break;
        case Entry::lower_near:
          break;
      }
    }
    diagonal_[i] = diagonal;
  }
}

// Phase one, one block at a time: its window starts at zero; row i adds a_ij x_i to the window's
// row j for each near pair, and then its own row's sum (a_ii x_i, its near and its far pairs
// gathered) to the window's row i, which by then holds the additions of the block's rows above.
template <class Value>
void UpperTriangle::accumulate_windows(const Value* near_value, const Value* far_value,
                                       const double* x) {
  const int n = rows_, blocks = static_cast<int>(window_end_.size());
#pragma omp for schedule(static)
  for (int block = 0; block < blocks; ++block) {
    const int first = block * kBlock, end = std::min(n, first + kBlock);
    double* window = window_.data() + window_start_[block];
    std::fill(window, window + (window_end_[block] - first), 0.0);
    const double* x_window = x + first;
    for (int i = first; i < end; ++i) {
      const double xi = x[i];
      // Two accumulators (even and odd pairs): a row's additions are a chain of dependent
      // additions otherwise; the split is fixed, so the bits do not depend on the threads.
      double even = diagonal_[i] * xi, odd = 0.0;
      std::int64_t k = near_offset_[i];
      const std::int64_t near_end = near_offset_[i + 1];
      for (; k + 1 < near_end; k += 2) {
        const std::uint16_t c0 = near_column_[k], c1 = near_column_[k + 1];
        const double v0 = static_cast<double>(near_value[k]);
        const double v1 = static_cast<double>(near_value[k + 1]);
        even += v0 * x_window[c0];
        odd += v1 * x_window[c1];
        window[c0] += v0 * xi;
        window[c1] += v1 * xi;
      }
      if (k < near_end) {
        const std::uint16_t c = near_column_[k];
        const double v = static_cast<double>(near_value[k]);
        even += v * x_window[c];
        window[c] += v * xi;
      }
      for (std::int64_t f = far_offset_[i]; f < far_offset_[i + 1]; ++f) {
        even += static_cast<double>(far_value[f]) * x[far_column_[f]];
      }
      window[i - first] += even + odd;
    }
  }
}

// Phase two, one block at a time: y_i is its block's window, then the windows of the
// kNearBlocks blocks before it that reach row i, nearest first; x . y summed as dot() sums.
void UpperTriangle::sum_windows(const double* x, double* y, std::vector<double>& partial) {
  const int n = rows_, blocks = static_cast<int>(window_end_.size());
#pragma omp for schedule(static)
  for (int block = 0; block < blocks; ++block) {
    const int first = block * kBlock, end = std::min(n, first + kBlock);
    const double* own = window_.data() + window_start_[block];
    for (int i = first; i < end; ++i) y[i] = own[i - first];
    for (int before = block - 1; before >= std::max(0, block - kNearBlocks); --before) {
      const int reach = std::min(end, window_end_[before]);
      const double* window = window_.data() + window_start_[before] - before * kBlock;
      for (int i = first; i < reach; ++i) y[i] += window[i];
    }
    double xy = 0.0;
    for (int i = first; i < end; ++i) xy += x[i] * y[i];
    partial[block] = xy;
  }
}

double UpperTriangle::multiply(const double* x, double* y, std::vector<double>& partial,
                               bool exact) {
  const int blocks = static_cast<int>(window_end_.size());
  partial.resize(blocks);
#pragma omp parallel if (blocks >= 4)
  {
    if (single_ && !exact) {
      accumulate_windows(near_single_.data(), far_single_.data(), x);
    } else {
      accumulate_windows(near_value_.data(), far_value_.data(), x);
    }
    sum_windows(x, y, partial);  // after the barrier that ends the loop above
  }
  double total = 0.0;
  for (int block = 0; block < blocks; ++block) total += partial[block];
  return total;
}

}  // namespace cosim::mps
