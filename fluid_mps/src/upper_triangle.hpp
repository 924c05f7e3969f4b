// The symmetric pressure matrix stored once for the CG products: each off-diagonal pair a_ij =
// a_ji is read once and used for both y_i (gathered) and y_j (scattered), half the bytes of a
// product over the full rows, which is bound by reading the matrix (docs/performance.md).
#pragma once

#include <cstdint>
#include <vector>

#include "cosim/fluid_mps/pressure_solver.hpp"

namespace cosim::mps {

// Rows are cut into fixed blocks of kBlock rows, the blocks of the CG's dot products. A pair
// whose column lies within kNearBlocks blocks after its row's block ("near") is kept once, in
// the row above; the additions it makes to later rows go to the row block's own window (a dense
// stretch of rows from the block's first row on), and each row then sums its block's window and
// the windows of the blocks before it in a fixed order. Pairs farther apart in index ("far": a
// periodic wrap, a long slab in cell order) are kept in both rows and gathered, as the full rows
// are. So every sum has one order for any thread count: the results are identical with one and
// with two threads. The bits differ from the full rows' product (another order of the same
// additions).
//
// The matrix must be symmetric in its values: the lower triangle's near entries are not read
// (the MPS Laplacian is: w(r_ij) = w(r_ji), tests/fluid_mps check it on assembled scenes).
class UpperTriangle {
 public:
  static constexpr int kBlock = 1024;
  static constexpr int kNearBlocks = 7;  // windows of up to 8 blocks: 16-bit offsets

  // From the rows of a symmetric matrix (entries in any order, repeated columns allowed; the
  // diagonal is the sum of a row's entries in its own column, where padding zeros go). With
  // `single_value`, the off-diagonal values are also kept rounded to float for multiply().
  void build(const SparseRows& m, bool single_value = false);
  // y = A x (y sized by the caller); returns x . y summed per block, the blocks in order. Reads
  // the float values when built with them, unless `exact` (the double values).
  double multiply(const double* x, double* y, std::vector<double>& partial, bool exact = false);

  int rows() const { return rows_; }
  std::int64_t near_entries() const { return near_offset_.empty() ? 0 : near_offset_.back(); }
  std::int64_t far_entries() const { return far_offset_.empty() ? 0 : far_offset_.back(); }

 private:
  void fill(const SparseRows& m);
  template <class Value>
  void accumulate_windows(const Value* near_value, const Value* far_value, const double* x);
  void sum_windows(const double* x, double* y, std::vector<double>& partial);

  int rows_ = 0;
  bool single_ = false;
  std::vector<double> diagonal_;
  std::vector<std::int64_t> near_offset_;   // row i's near pairs: [near_offset_[i], [i + 1])
  std::vector<std::uint16_t> near_column_;  // column - first row of the row's block
  std::vector<double> near_value_;
  std::vector<float> near_single_;
  std::vector<std::int64_t> far_offset_;
  std::vector<int> far_column_;
  std::vector<double> far_value_;
  std::vector<float> far_single_;
  std::vector<int> window_end_;             // per block: one past the last row its window holds
  std::vector<std::int64_t> window_start_;  // per block: its window's place in window_
  std::vector<double> window_;
};

}  // namespace cosim::mps
