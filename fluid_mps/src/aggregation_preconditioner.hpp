// Two-level additive preconditioner of the pressure Poisson equation: Jacobi on the unknowns
// plus an exact solve on aggregates of strongly connected unknowns,
//   M^-1 r = D^-1 r + P (P^T A P)^-1 P^T r,
// with P the piecewise-constant prolongation of the aggregates (aggregation as in Vanek, Mandel
// & Brezina 1996, "Algebraic multigrid by smoothed aggregation", without the smoothing of P; the
// additive two-level form as in Toselli & Widlund 2005, ch. 3). The coarse space carries the
// smooth error that makes Jacobi's iterations grow with resolution, so CG's iterations stay
// about constant (docs/performance.md). Every sum runs in row order (the coarse assembly splits
// the aggregates over threads, each coarse entry summed by one of them), so the result does not
// depend on the thread count.
#pragma once

#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <cstdint>
#include <vector>

#include "cosim/fluid_mps/pressure_solver.hpp"

namespace cosim::mps {

// Strength threshold of the aggregation. On MPS Laplacians of 6 k and 25 k unknowns (2D, radius
// 4 l0) and 26 k (3D, radius 3.1 l0) it gave aggregates of 13 / 13 / 26 unknowns and 26 / 26 / 27
// CG iterations to 1e-8 from zero against Jacobi's 169 / 327 / 96; 0.5 gave aggregates of
// 9 / 9 / 15 and 23 / 23 / 23 iterations with a denser coarse matrix (docs/performance.md).
inline constexpr double kAggregationStrength = 0.3;

// From kAggregationSplitRows rows on, the first pass of the aggregation runs on
// kAggregationStretches equal stretches of rows side by side (see build_aggregates).
inline constexpr int kAggregationSplitRows = 4096;
inline constexpr int kAggregationStretches = 2;

class AggregationPreconditioner {
 public:
  // Builds the aggregates, the coarse matrix and its Cholesky factor for `matrix`. A neighbour
  // j is strong for row i when -a_ij >= strength * max_k(-a_ik) over i's off-diagonal entries.
  // Returns false (and apply() is then plain Jacobi) when the coarse matrix is not positive
  // definite, which happens only if `matrix` is not.
  bool setup(const SparseRows& matrix, double strength = kAggregationStrength);
  // z = D^-1 r + P A_c^-1 P^T r; returns r . z summed over blocks of `block` rows, the blocks'
  // sums (kept in `partial`) added in order, as the CG's dot products sum.
  double apply(const std::vector<double>& r, std::vector<double>& z, int block,
               std::vector<double>& partial);
  // Keys the aggregates of the last setup() by `row_keys` (a key per row, e.g. a particle id, in
  // [0, key_count)), so that reuse() can find them for another matrix of the same keys.
  void remember_keys(const std::vector<int>& row_keys, int key_count);
  // The last setup's aggregates and coarse factor for `matrix`: each row joins the aggregate its
  // key had (a key that had none gets the Jacobi part only), the diagonal is `matrix`'s own.
  // M^-1 = D^-1 + P A_c^-1 P^T stays symmetric positive definite, so CG converges with it;
  // A_c is the old P^T A P. Returns false if there is nothing to reuse.
  bool reuse(const SparseRows& matrix, const std::vector<int>& row_keys);
  // The keyed aggregates and coarse matrix (kept and age are the caller's), and back: import
  // factorises the coarse matrix again (the same matrix, so the same factor) and returns false
  // if it is not positive definite.
  void export_setup(PressureSetupState& state) const;
  bool import_setup(const PressureSetupState& state);

 private:
  void build_aggregates(const SparseRows& matrix, double strength);
  int greedy_pass(const SparseRows& matrix, double strength, int begin, int end);
  int join_pass(const SparseRows& matrix, int begin, int end);
  void build_coarse_matrix(const SparseRows& matrix);
  void gather_members(int rows);
  bool factorize();  // the coarse matrix's LDL^T; false if it is not positive definite

  std::vector<int> aggregate_of_key_;  // remember_keys: the aggregate of each key, or -1

  std::vector<double> inverse_diagonal_;
  std::vector<double> strong_;               // strength threshold of each row
  std::vector<int> aggregate_;               // aggregate of each row
  std::vector<int> member_offset_, member_;  // rows of each aggregate, in row order
  std::vector<int> member_cursor_;
  std::vector<int> joined_;                   // see join_pass
  std::vector<int> first_count_, own_count_;  // pass-1 and pass-3 aggregates before a stretch
  struct Scratch {                            // one per thread of the coarse assembly
    std::vector<int> touched, slot_of;        // coarse rows seen in the current column, their slots
    std::vector<double> row_sum;
    std::vector<Eigen::Triplet<double>> lower;
  };
  std::vector<Scratch> scratch_;
  std::vector<Eigen::Triplet<double>> lower_;  // coarse entries on and below the diagonal
  int aggregate_count_ = 0;
  bool factored_ = false;
  Eigen::SparseMatrix<double> coarse_;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower> factor_;
  Eigen::VectorXd coarse_rhs_, coarse_solution_;
};

}  // namespace cosim::mps
