// Symmetric positive definite sparse system of the pressure Poisson equation and its
// Jacobi-preconditioned conjugate gradient solver.
#pragma once

#include <cstdint>
#include <vector>

namespace cosim::mps {

// Compressed sparse rows; each row stores its diagonal too.
struct SparseRows {
  std::vector<std::int64_t> offset{0};
  std::vector<int> column;
  std::vector<double> value;
  int rows() const { return static_cast<int>(offset.size()) - 1; }
};

struct PcgResult {
  int iterations = 0;
  double relative_residual = 0.0;  // |b - A x| / |b| (recursive residual)
  bool converged = false;
};

enum class Preconditioner { jacobi, incomplete_cholesky };

// Solves A x = b from the initial guess in x. Stops when |r| <= tolerance |b|.
// Jacobi: own parallel PCG whose dot products are summed in fixed blocks, so the result is
// identical for any thread count. Incomplete Cholesky: Eigen's serial IC(0)-with-shift
// preconditioned CG (fewer, dearer iterations; deterministic as it runs on one thread).
PcgResult solve_pcg(const SparseRows& matrix, const std::vector<double>& rhs,
                    std::vector<double>& x, double tolerance, int max_iterations,
                    Preconditioner preconditioner = Preconditioner::jacobi);

}  // namespace cosim::mps
