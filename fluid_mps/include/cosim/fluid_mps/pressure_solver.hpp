// Symmetric positive definite sparse system of the pressure Poisson equation and its
// preconditioned conjugate gradient solvers.
#pragma once

#include <cstdint>
#include <memory>
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

// jacobi: diagonal scaling; iterations grow about as the square root of the unknowns.
// incomplete_cholesky: Eigen's serial IC(0)-with-shift CG (fewer, dearer iterations).
// amg: one V-cycle of hypre's BoomerAMG (HMIS coarsening, extended+i interpolation, hybrid
// symmetric Gauss-Seidel smoothing) per iteration; iterations stay about constant with the
// resolution. The hierarchy is built for every solve: the matrix changes as particles move, and a
// hierarchy kept between steps would make a restarted run differ from an uninterrupted one.
// automatic: jacobi below kAmgFromUnknowns unknowns, amg from there on (a choice made from the
// system alone, so runs and restarts stay bit-identical).
// aggregation: Jacobi plus an exact solve on aggregates of strongly connected unknowns
// (aggregation_preconditioner.hpp); iterations stay about constant with the resolution at the
// cost of about one extra pass over the matrix a solve, all of it our own code.
enum class Preconditioner { jacobi, incomplete_cholesky, amg, automatic, aggregation };

// Measured crossover of one-thread step cost on the 2D dam break (BM_DamBreakStep, CPU time,
// alternating runs; docs/performance.md), with the interleaved CG product: Jacobi / AMG step time
// 0.64-1.15 (mean 0.92) at 3 800 unknowns (a/l0 = 40), 1.04-1.08 at 5 300 (48), 1.41 at 7 100
// (56) and 1.13 at 9 100 (64); below 3 800 Jacobi wins. The ratio crosses 1 near 4 600.
constexpr int kAmgFromUnknowns = 4500;
// 3D (radius 3.1 l0): Jacobi was 1.2 times faster than AMG at every size measured (9.7 k to
// 37.6 k particles), its iterations growing as N^(1/3) (33 to 58); at that rate they reach
// about 120 near 300 k unknowns, where the AMG step (9-10 iterations) is expected to win. The
// switch point is that extrapolation, not a measurement.
constexpr int kAmgFromUnknowns3d = 200000;

// y = A x; each row summed in the order of its entries (the bits of the plain loop). With
// `single_precision`, each value is first rounded to float (the bits of the plain loop over
// double(float(value))), as the CG products do with set_single_precision_product.
void multiply(const SparseRows& matrix, const std::vector<double>& x, std::vector<double>& y,
              bool single_precision = false);

// Solves A x = b from the initial guess in x. Stops when |r| <= tolerance |b|. The Krylov loop is
// our own, parallel, with dot products summed in fixed blocks, so the result is identical for
// any thread count (the AMG cycle and incomplete Cholesky run on one thread).
PcgResult solve_pcg(const SparseRows& matrix, const std::vector<double>& rhs,
                    std::vector<double>& x, double tolerance, int max_iterations,
                    Preconditioner preconditioner = Preconditioner::jacobi);

// Work vectors of the conjugate gradients (residual, preconditioned residual, direction,
// product, per-block partial sums; the matrix's column indices in 16 bits when they fit).
struct CgWork {
  std::vector<double> r, z, p, q, partial;
  std::vector<std::uint16_t> short_column;
  bool single_precision = false;  // the CG products read float copies of the values
  std::vector<float> single_value;
};

// A pressure solver that keeps its work arrays (and the AMG library objects) between solves, so
// a time step allocates nothing once the particle count has settled.
class PressureSolver {
 public:
  explicit PressureSolver(Preconditioner preconditioner = Preconditioner::amg,
                          int amg_from_unknowns = kAmgFromUnknowns);
  ~PressureSolver();
  PressureSolver(PressureSolver&&) noexcept;
  PressureSolver& operator=(PressureSolver&&) noexcept;

  // `hierarchy_matrix` (amg only, optional): a sparser matrix of the same unknowns and
  // boundary conditions from which the multigrid hierarchy is built instead (a short-radius
  // Laplacian of the same particles); conjugate gradients still solve `matrix`.
  PcgResult solve(const SparseRows& matrix, const std::vector<double>& rhs, std::vector<double>& x,
                  double tolerance, int max_iterations,
                  const SparseRows* hierarchy_matrix = nullptr);
  Preconditioner preconditioner() const { return preconditioner_; }
  // The products of the CG iterations read the matrix values rounded to float (fewer bytes an
  // entry; sums, vectors and the initial residual stay double). Off by default: it changes the
  // bits of the solution (docs/performance.md, single-precision product).
  void set_single_precision_product(bool on) { work_.single_precision = on; }
  bool single_precision_product() const { return work_.single_precision; }
  // Whether a system of `rows` unknowns is preconditioned by multigrid.
  bool uses_amg(int rows) const {
    return preconditioner_ == Preconditioner::amg ||
           (preconditioner_ == Preconditioner::automatic && rows >= amg_from_unknowns_);
  }

 private:
  struct Amg;          // hypre objects; the header includes no hypre or MPI header
  struct Aggregation;  // the two-level preconditioner (Eigen's sparse Cholesky inside)
  Preconditioner preconditioner_;
  int amg_from_unknowns_;
  std::unique_ptr<Amg> amg_;
  std::unique_ptr<Aggregation> aggregation_;
  CgWork work_;
  std::vector<double> inverse_diagonal_;
};

}  // namespace cosim::mps
