// Symmetric positive definite sparse system of the pressure Poisson equation and its
// preconditioned conjugate gradient solvers.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace cosim::mps {

// Compressed sparse rows; each row stores its diagonal too.
struct SparseRows {
  std::vector<std::int64_t> offset{0};
  std::vector<int> column;
  std::vector<double> value;
  // Set by an assembly whose rows start with their diagonal entry (any later entry in the
  // diagonal's column is a zero): invert_diagonal() then reads it without a scan of the row.
  bool diagonal_first = false;
  int rows() const { return static_cast<int>(offset.size()) - 1; }
};

struct PcgResult {
  int iterations = 0;
  double relative_residual = 0.0;  // |b - A x| / |b| (recursive residual)
  bool converged = false;
  double setup_seconds = 0.0;  // wall time of the preconditioner's set-up (PressureSolver)
};

// jacobi: diagonal scaling; iterations grow about as the square root of the unknowns.
// incomplete_cholesky: Eigen's serial IC(0)-with-shift CG (fewer, dearer iterations).
// amg: one V-cycle of hypre's BoomerAMG (HMIS coarsening, extended+i interpolation, hybrid
// symmetric Gauss-Seidel smoothing) per iteration; iterations stay about constant with the
// resolution. The hierarchy is built for every solve: the matrix changes as particles move, and a
// hierarchy kept between steps would make a restarted run differ from an uninterrupted one.
// aggregation: Jacobi plus an exact solve on aggregates of strongly connected unknowns
// (aggregation_preconditioner.hpp); iterations stay about constant with the resolution (20-26 a
// step) for a set-up of about two passes over the matrix, all of it our own code. Its set-up
// is kept over several solves (set_setup_reuse): the aggregates by particle id, the coarse
// factor as it was; the state travels in checkpoints, so restarts keep the bits.
// automatic: jacobi below aggregation_from_unknowns unknowns, aggregation from there on (a
// choice made from the system alone, so runs and restarts stay bit-identical).
enum class Preconditioner { jacobi, incomplete_cholesky, amg, automatic, aggregation };

// Where `automatic` switches from jacobi to aggregation, from the one-thread step cost of the
// dam breaks (BM_DamBreakStep, BM_Column3dStep: three alternating rounds, sums of CPU time,
// docs/performance.md). 2D (radius 4 l0): aggregation / jacobi 0.99 at 350 unknowns (a/l0 =
// 10), 0.75 at 1 100 (20), 0.67 at 3 800 (40), 0.43 at 14 000 (80). 3D (radius 3.1 l0): 0.97
// at 3 200 unknowns (a/l0 = 8), 1.03 at 8 100 (12), 0.78 at 16 100 (16). AMG (hypre) took
// 1.5-2.2 times aggregation's step at every 2D size, so automatic no longer takes it.
constexpr int kAggregationFromUnknowns = 1000;
constexpr int kAggregationFromUnknowns3d = 10000;

// A reused aggregation set-up is rebuilt once a solve takes more than this many CG iterations
// beyond its first solve. On the dam break (a/l0 = 80) and the 3D column (a/l0 = 16) reuse over
// up to 10 solves raised the mean iterations from 25.2 to 26.3 and 24.3 to 25.1, and cut the
// one-thread step by 8-13 % and 8-9 % (docs/performance.md).
constexpr int kSetupReuseMargin = 2;

// What a pressure solver carries from one solve to the next that changes its results: the
// aggregation's set-up while it is reused (PressureSolver::set_setup_reuse). Saved with the
// particles in checkpoints and restart files, so a run continued from one gives the same bits.
struct PressureSetupState {
  bool kept = false;  // there is a set-up to reuse; the rest is empty without one
  int age = 0;        // solves since the set-up was built
  int base_iterations = 0, last_iterations = 0;  // CG iterations of its first and last solve
  std::vector<int> aggregate_of_key;             // aggregate of each particle id, or -1
  int aggregate_count = 0;
  std::vector<int> coarse_row, coarse_column;  // A_c's lower triangle, column by column
  std::vector<double> coarse_value;
};

// What is wrong with a set-up state read from a file, if anything: `field` names the part as the
// files name it (counts: the age and the aggregate count; aggregate_of_key; coarse_row), `what`
// says how. Checked: a non-negative age,
// at least one aggregate, at most `particles` keys, each key's aggregate in [-1, count), the
// coarse arrays of one length, every coarse entry in the lower triangle.
struct SetupProblem {
  std::string field, what;
};
std::optional<SetupProblem> find_setup_problem(const PressureSetupState& state,
                                               std::size_t particles);

// y = A x; each row summed in the order of its entries (the bits of the plain loop). With
// `single_precision`, each value is first rounded to float (the bits of the plain loop over
// double(float(value))), as the CG products do with set_single_precision_product.
void multiply(const SparseRows& matrix, const std::vector<double>& x, std::vector<double>& y,
              bool single_precision = false);

// inverse[i] = 1 / a_ii, the entries on row i's diagonal column summed (as the product sums
// them; padding entries are zeros there), or 1 where that sum is not positive.
void invert_diagonal(const SparseRows& matrix, std::vector<double>& inverse);

// Solves A x = b from the initial guess in x. Stops when |r| <= tolerance |b|. The Krylov loop is
// our own, parallel, with dot products summed in fixed blocks, so the result is identical for
// any thread count (the AMG cycle and incomplete Cholesky run on one thread).
PcgResult solve_pcg(const SparseRows& matrix, const std::vector<double>& rhs,
                    std::vector<double>& x, double tolerance, int max_iterations,
                    Preconditioner preconditioner = Preconditioner::jacobi);

// Work vectors of the conjugate gradients (residual, preconditioned residual, direction,
// product, per-block partial sums) and the matrix as the products read it (row_product.hpp in
// fluid_mps/src: the rows interleaved by groups, with double or float values; column indices in
// 16 bits when they fit).
struct CgWork {
  std::vector<double> r, z, p, q, partial;
  bool single_precision = false;  // the CG products read float copies of the values
  std::vector<std::int64_t> group_start;
  std::vector<double> group_value;
  std::vector<float> group_single_value;
  std::vector<std::uint16_t> group_short_column;
  std::vector<int> group_column;
};

class UpperTriangle;  // upper_triangle.hpp (fluid_mps/src)

// A pressure solver that keeps its work arrays (and the AMG library objects) between solves, so
// a time step allocates nothing once the particle count has settled.
class PressureSolver {
 public:
  explicit PressureSolver(Preconditioner preconditioner = Preconditioner::amg,
                          int aggregation_from_unknowns = kAggregationFromUnknowns);
  ~PressureSolver();
  PressureSolver(PressureSolver&&) noexcept;
  PressureSolver& operator=(PressureSolver&&) noexcept;

  // `hierarchy_matrix` (amg only, optional): a sparser matrix of the same unknowns and
  // boundary conditions from which the multigrid hierarchy is built instead (a short-radius
  // Laplacian of the same particles); conjugate gradients still solve `matrix`.
  PcgResult solve(const SparseRows& matrix, const std::vector<double>& rhs, std::vector<double>& x,
                  double tolerance, int max_iterations,
                  const SparseRows* hierarchy_matrix = nullptr);
  // Reuse of the aggregation's set-up (aggregates and coarse factor) over up to `max_solves`
  // solves (1: a new set-up every solve). A set-up is reused while the CG iterations stay within
  // kSetupReuseMargin of those of its first solve; each row finds its aggregate by its key (the
  // particle id, set_row_keys), and the Jacobi part always takes the current diagonal.
  void set_setup_reuse(int max_solves) { setup_reuse_ = max_solves; }
  // The key of each row of the next solves (kept by pointer), in [0, key_count).
  void set_row_keys(const std::vector<int>* row_keys, int key_count) {
    row_keys_ = row_keys;
    key_count_ = key_count;
  }
  PressureSetupState setup_state() const;
  // A state from setup_state(), e.g. of a checkpoint; refactorises the coarse matrix.
  void restore_setup(const PressureSetupState& state);
  Preconditioner preconditioner() const { return preconditioner_; }
  // The products of the CG iterations read the matrix values rounded to float (fewer bytes an
  // entry; sums, vectors and the initial residual stay double, and true residuals with the
  // double values decide the stop). Off by default: it changes the bits of the solution and
  // gains only where the matrix outgrows the caches in double but not in float (large 3D
  // systems, honami_field in 2D; docs/performance.md, single-precision product).
  void set_single_precision_product(bool on) { work_.single_precision = on; }
  bool single_precision_product() const { return work_.single_precision; }
  // The products of the CG read the upper triangle only (each pair a_ij = a_ji once, half the
  // bytes; the matrix must be symmetric in its values), summed in fixed row blocks so the
  // result does not depend on the thread count; another order of the additions than the full
  // rows', so other bits (upper_triangle.hpp, docs/performance.md).
  void set_upper_triangle_product(bool on) { upper_triangle_ = on; }
  bool upper_triangle_product() const { return upper_triangle_; }
  // The preconditioner a system of `rows` unknowns gets (automatic resolved).
  Preconditioner preconditioner_for(int rows) const {
    if (preconditioner_ != Preconditioner::automatic) return preconditioner_;
    return rows >= aggregation_from_unknowns_ ? Preconditioner::aggregation
                                              : Preconditioner::jacobi;
  }
  // Whether a system of `rows` unknowns is preconditioned by hypre's multigrid.
  bool uses_amg(int rows) const { return preconditioner_for(rows) == Preconditioner::amg; }

 private:
  struct Amg;              // hypre objects; the header includes no hypre or MPI header
  struct Aggregation;      // the two-level preconditioner (Eigen's sparse Cholesky inside)
  UpperTriangle* upper();  // the triangle's storage when its product is on, else null
  Preconditioner preconditioner_;
  int aggregation_from_unknowns_;
  std::unique_ptr<Amg> amg_;
  std::unique_ptr<Aggregation> aggregation_;
  CgWork work_;
  bool upper_triangle_ = false;
  std::unique_ptr<UpperTriangle> upper_;
  std::vector<double> inverse_diagonal_;
  int setup_reuse_ = 1;
  const std::vector<int>* row_keys_ = nullptr;
  int key_count_ = 0;
  bool setup_kept_ = false;  // the aggregation's last set-up is keyed and may be reused
  int setup_age_ = 0, base_iterations_ = 0, last_iterations_ = 0;
};

}  // namespace cosim::mps
