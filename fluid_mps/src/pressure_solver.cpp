#include "cosim/fluid_mps/pressure_solver.hpp"

#include <Eigen/IterativeLinearSolvers>
#include <Eigen/SparseCore>
#include <algorithm>
#include <cmath>

#include <omp.h>

#include "aggregation_preconditioner.hpp"
#include "amg_preconditioner.hpp"
#include "cosim/fluid_mps/stage_seconds.hpp"
#include "row_product.hpp"
#include "upper_triangle.hpp"

namespace cosim::mps {
namespace {

// Rows per block of the dot products; the upper triangle's windows use the same blocks.
constexpr int kBlock = UpperTriangle::kBlock;

// With float products, the factor by which |r| falls between two true residuals (see
// conjugate_gradients): the initial, one on the way and the last, three double products in a
// solve from a relative residual of 1 to 1e-8 (1e-3 took four, with the same iterations in the
// 2D dam break with aggregation, 0.2-1 % fewer than now with Jacobi). With no true residual on the
// way the first one read 1.5e-7 at the tolerance, and CG stalled there for hundreds of
// iterations.
constexpr double kReplacementDrop = 1e-4;

// Deterministic parallel dot product: per-block partial sums, then a serial sum of the blocks.
double dot(const std::vector<double>& a, const std::vector<double>& b,
           std::vector<double>& partial) {
  const int n = static_cast<int>(a.size());
  const int blocks = (n + kBlock - 1) / kBlock;
  partial.assign(blocks, 0.0);
#pragma omp parallel for schedule(static) if (blocks >= 4)
  for (int block = 0; block < blocks; ++block) {
    const int end = std::min(n, (block + 1) * kBlock);
    double sum = 0.0;
    for (int i = block * kBlock; i < end; ++i) sum += a[i] * b[i];
    partial[block] = sum;
  }
  double total = 0.0;
  for (double p : partial) total += p;
  return total;
}

PcgResult solve_incomplete_cholesky(const SparseRows& matrix, const std::vector<double>& rhs,
                                    std::vector<double>& x, double tolerance, int max_iterations) {
  const int n = matrix.rows();
  std::vector<Eigen::Triplet<double>> entries;
  entries.reserve(matrix.column.size());
  for (int i = 0; i < n; ++i) {
    for (std::int64_t k = matrix.offset[i]; k < matrix.offset[i + 1]; ++k) {
      if (matrix.value[k] != 0.0) entries.emplace_back(i, matrix.column[k], matrix.value[k]);
    }
  }
  Eigen::SparseMatrix<double> a(n, n);
  a.setFromTriplets(entries.begin(), entries.end());
  Eigen::ConjugateGradient<Eigen::SparseMatrix<double>, Eigen::Lower | Eigen::Upper,
                           Eigen::IncompleteCholesky<double>>
      cg;
  cg.setTolerance(tolerance);
  cg.setMaxIterations(max_iterations);
  cg.compute(a);
  PcgResult result;
  if (cg.info() != Eigen::Success) return result;
  const Eigen::Map<const Eigen::VectorXd> b(rhs.data(), n);
  Eigen::Map<Eigen::VectorXd> guess(x.data(), n);
  const Eigen::VectorXd solution = cg.solveWithGuess(b, Eigen::VectorXd(guess));
  guess = solution;
  result.iterations = static_cast<int>(cg.iterations());
  result.relative_residual = cg.error();
  result.converged = cg.info() == Eigen::Success;
  return result;
}

// The Krylov loop below fuses the vector passes of one iteration into three parallel loops over
// the blocks of dot(): each block's partial sums are accumulated in item order and the blocks
// are summed in order, exactly as dot() does, so the bits are those of the plain loop.
int block_count(int n) {
  return (n + kBlock - 1) / kBlock;
}

// The first row of `thread`'s share of a product over `rows` rows: whole groups of kRowGroup
// rows, split so that each thread gets about the same number of entries (rows near the surface
// are shorter; a split by row count left one thread 12 % more of honami_field's entries).
int first_row_of_share(const std::vector<std::int64_t>& offset, int rows, int thread, int team) {
  if (thread == 0) return 0;
  const int groups = rows / kRowGroup;
  const std::int64_t target = offset[rows] * thread / team;
  int low = 0, high = groups;  // the first group whose first entry is at or past the target
  while (low < high) {
    const int middle = (low + high) / 2;
    if (offset[static_cast<std::size_t>(middle) * kRowGroup] < target) {
      low = middle + 1;
    } else {
      high = middle;
    }
  }
  return low * kRowGroup;
}

// q = A p; returns p . q. The product's rows are split over the threads by entries, not by
// blocks: with an odd number of blocks a split by blocks gave one thread a block more (6 of 11
// in honami_field, 58 % of the product's samples on one thread). A row's sum does not depend on
// who computes it, and the dot product is then summed by blocks as dot() sums it.
double multiply_dot(const RowView& m, const std::vector<double>& p, std::vector<double>& q,
                    std::vector<double>& partial) {
  const int n = m.m->rows(), blocks = block_count(n);
  partial.resize(blocks);
#pragma omp parallel if (blocks >= 4)
  {
    const int thread = omp_get_thread_num(), team = omp_get_num_threads();
    // Whole groups of kRowGroup rows a thread (the last thread takes the remainder).
    const int begin = first_row_of_share(m.m->offset, n, thread, team);
    const int end = thread + 1 == team ? n : first_row_of_share(m.m->offset, n, thread + 1, team);
    multiply_rows(m, p.data(), begin, end, q.data());
#pragma omp barrier
#pragma omp for schedule(static)
    for (int block = 0; block < blocks; ++block) {
      const int block_end = std::min(n, (block + 1) * kBlock);
      double pq = 0.0;
      for (int i = block * kBlock; i < block_end; ++i) pq += p[i] * q[i];
      partial[block] = pq;
    }
  }
  double total = 0.0;
  for (int block = 0; block < blocks; ++block) total += partial[block];
  return total;
}

// One pass over the blocks of dot() that sets the residual: `prepare(begin, end)` runs first on
// each block, then r_i = next_residual(i) for its rows; with `inverse_diagonal` also z = D^-1 r.
// Returns r . r and, with the diagonal, r . z in `rz`, each summed as dot() sums.
template <class Prepare, class NextResidual>
double residual_pass(std::vector<double>& r, std::vector<double>& z,
                     const std::vector<double>* inverse_diagonal, std::vector<double>& partial,
                     double& rz, Prepare&& prepare, NextResidual&& next_residual) {
  const int n = static_cast<int>(r.size()), blocks = block_count(n);
  partial.resize(2 * static_cast<std::size_t>(blocks));
  if (inverse_diagonal) z.resize(n);
#pragma omp parallel for schedule(static) if (blocks >= 4)
  for (int block = 0; block < blocks; ++block) {
    const int end = std::min(n, (block + 1) * kBlock);
    prepare(block * kBlock, end);
    double rr_sum = 0.0, rz_sum = 0.0;
    for (int i = block * kBlock; i < end; ++i) {
      r[i] = next_residual(i);
      if (inverse_diagonal) {
        z[i] = (*inverse_diagonal)[i] * r[i];
        rz_sum += r[i] * z[i];
      }
      rr_sum += r[i] * r[i];
    }
    partial[2 * block] = rr_sum;
    partial[2 * block + 1] = rz_sum;
  }
  double rr = 0.0;
  rz = 0.0;
  for (int block = 0; block < blocks; ++block) {
    rr += partial[2 * block];
    rz += partial[2 * block + 1];
  }
  return rr;
}

// x += alpha p, r -= alpha q (and z, r . r, r . z as residual_pass()).
double update_residual(double alpha, const std::vector<double>& p, const std::vector<double>& q,
                       std::vector<double>& x, std::vector<double>& r, std::vector<double>& z,
                       const std::vector<double>* inverse_diagonal, std::vector<double>& partial,
                       double& rz) {
  return residual_pass(
      r, z, inverse_diagonal, partial, rz, [](int, int) {},
      [&](int i) {
        x[i] += alpha * p[i];
        return r[i] - alpha * q[i];
      });
}

// r = b - A x with the matrix `m` (q is overwritten; z, r . r, r . z as residual_pass()).
double true_residual(const RowView& m, const std::vector<double>& rhs, const std::vector<double>& x,
                     std::vector<double>& q, std::vector<double>& r, std::vector<double>& z,
                     const std::vector<double>* inverse_diagonal, std::vector<double>& partial,
                     double& rz) {
  return residual_pass(
      r, z, inverse_diagonal, partial, rz,
      [&](int begin, int end) { multiply_rows(m, x.data(), begin, end, q.data()); },
      [&](int i) { return rhs[i] - q[i]; });
}

// The products of one solve: the full rows (`rows`, float values with single precision) or,
// with `upper`, the upper triangle built from them (float values too with single precision);
// true residuals (the initial one, and those of residual replacement) read the double values.
struct SolveProducts {
  RowView rows, exact;
  UpperTriangle* upper = nullptr;

  SolveProducts(const SparseRows& matrix, CgWork& work, UpperTriangle* upper_triangle) {
    upper = upper_triangle;
    const bool single = work.single_precision;
    if (upper) {
      upper->build(matrix, single);  // with floats for the iterations, doubles for the rest
      return;
    }
    rows = row_view(matrix, work, single);
    exact = exact_view(rows);
  }

  // q = A p with the products of the iterations; returns p . q.
  double multiply_dot(const std::vector<double>& p, std::vector<double>& q,
                      std::vector<double>& partial) const {
    if (upper) return upper->multiply(p.data(), q.data(), partial);
    return ::cosim::mps::multiply_dot(rows, p, q, partial);
  }

  // r = b - A x with the double values (q overwritten; z, r . r, r . z as residual_pass()).
  double true_residual(const std::vector<double>& rhs, const std::vector<double>& x,
                       std::vector<double>& q, std::vector<double>& r, std::vector<double>& z,
                       const std::vector<double>* inverse_diagonal, std::vector<double>& partial,
                       double& rz) const {
    if (upper) {
      upper->multiply(x.data(), q.data(), partial, true);
      return residual_pass(
          r, z, inverse_diagonal, partial, rz, [](int, int) {},
          [&](int i) { return rhs[i] - q[i]; });
    }
    return ::cosim::mps::true_residual(exact, rhs, x, q, r, z, inverse_diagonal, partial, rz);
  }
};

// Preconditioned conjugate gradients from the guess in x; `precondition(r, z)` sets z = M^-1 r and
// returns r . z (summed as dot() sums it), or with `inverse_diagonal` the Jacobi step is fused into
// the residual update.
template <class Precondition>
PcgResult conjugate_gradients(const SparseRows& matrix, const std::vector<double>& rhs,
                              std::vector<double>& x, double tolerance, int max_iterations,
                              CgWork& work, UpperTriangle* upper,
                              const std::vector<double>* inverse_diagonal,
                              Precondition&& precondition) {
  const int n = matrix.rows();
  std::vector<double>&r = work.r, &z = work.z, &p = work.p, &q = work.q;
  PcgResult result;
  const double rhs_norm = std::sqrt(dot(rhs, rhs, work.partial));
  if (rhs_norm == 0.0) {
    std::fill(x.begin(), x.end(), 0.0);
    result.converged = true;
    return result;
  }
  r.resize(n);
  p.resize(n);
  q.resize(n);
  // The initial residual is taken with the double matrix; with single values only the products
  // of the iterations use the rounded matrix (a relative change of at most 2^-24 an entry).
  const SolveProducts products(matrix, work, upper);
  double unused_rz = 0.0;
  const double rr0 = products.true_residual(rhs, x, q, r, z, nullptr, work.partial, unused_rz);
  double rz = precondition(r, z);
#pragma omp parallel for schedule(static) if (n >= 4096)
  for (int i = 0; i < n; ++i) p[i] = z[i];
  double residual = std::sqrt(rr0) / rhs_norm;
  // With float products the recursive residual r drifts from b - A x (each product is off by up
  // to 2^-24 an entry), and CG would converge on the rounded matrix, to about 1e-7 of |b| on
  // the double one. Residual replacement (the "reliable updates" of Sleijpen & van der Vorst
  // 1996, Computing 56, 141-163): whenever |r| has fallen by kReplacementDrop since the last
  // true residual, and before stopping, r is recomputed as b - A x with the double matrix and
  // CG goes on from it, so the stop is judged on the double system, as without float products.
  double last_true_norm = residual * rhs_norm;
  int iteration = 0;
  while (residual > tolerance && iteration < max_iterations) {
    const double pq = products.multiply_dot(p, q, work.partial);
    if (!(pq > 0.0)) break;  // loss of positive definiteness or breakdown
    const double alpha = rz / pq;
    double rz_next = 0.0;
    double rr = update_residual(alpha, p, q, x, r, z, inverse_diagonal, work.partial, rz_next);
    if (work.single_precision && (std::sqrt(rr) <= tolerance * rhs_norm ||
                                  std::sqrt(rr) < kReplacementDrop * last_true_norm)) {
      rr = products.true_residual(rhs, x, q, r, z, inverse_diagonal, work.partial, rz_next);
      last_true_norm = std::sqrt(rr);
    }
    if (!inverse_diagonal) rz_next = precondition(r, z);
    const double beta = rz_next / rz;
    rz = rz_next;
#pragma omp parallel for schedule(static) if (n >= 4096)
    for (int i = 0; i < n; ++i) p[i] = z[i] + beta * p[i];
    residual = std::sqrt(rr) / rhs_norm;
    ++iteration;
  }
  result.iterations = iteration;
  result.relative_residual = residual;
  result.converged = residual <= tolerance;
  return result;
}

}  // namespace

struct PressureSolver::Amg {
  AmgPreconditioner cycle;
};

struct PressureSolver::Aggregation {
  AggregationPreconditioner two_level;
};

PressureSolver::PressureSolver(Preconditioner preconditioner, int aggregation_from_unknowns)
    : preconditioner_(preconditioner), aggregation_from_unknowns_(aggregation_from_unknowns) {}
PressureSolver::~PressureSolver() = default;
PressureSolver::PressureSolver(PressureSolver&&) noexcept = default;
PressureSolver& PressureSolver::operator=(PressureSolver&&) noexcept = default;

UpperTriangle* PressureSolver::upper() {
  if (!upper_triangle_) return nullptr;
  if (!upper_) upper_ = std::make_unique<UpperTriangle>();
  return upper_.get();
}

std::optional<SetupProblem> find_setup_problem(const PressureSetupState& state,
                                               std::size_t particles) {
  if (state.age < 0) return SetupProblem{"counts", "holds a negative age"};
  if (state.aggregate_count <= 0) return SetupProblem{"counts", "holds no aggregate"};
  if (state.aggregate_of_key.size() > particles) {
    return SetupProblem{"aggregate_of_key", "has more keys than there are particles"};
  }
  for (const int a : state.aggregate_of_key) {
    if (a < -1 || a >= state.aggregate_count) {
      return SetupProblem{"aggregate_of_key", "names an aggregate that does not exist"};
    }
  }
  const std::size_t entries = state.coarse_value.size();
  if (state.coarse_row.size() != entries || state.coarse_column.size() != entries) {
    return SetupProblem{"coarse_row", "and the coarse columns and values differ in length"};
  }
  for (std::size_t k = 0; k < entries; ++k) {
    const int row = state.coarse_row[k], column = state.coarse_column[k];
    if (column < 0 || row < column || row >= state.aggregate_count) {
      return SetupProblem{"coarse_row",
                          "holds an entry outside the coarse matrix's lower triangle"};
    }
  }
  return std::nullopt;
}

PressureSetupState PressureSolver::setup_state() const {
  PressureSetupState state;
  if (!setup_kept_ || !aggregation_) return state;
  state.kept = true;
  state.age = setup_age_;
  state.base_iterations = base_iterations_;
  state.last_iterations = last_iterations_;
  aggregation_->two_level.export_setup(state);
  return state;
}

void PressureSolver::restore_setup(const PressureSetupState& state) {
  setup_kept_ = false;
  if (!state.kept) return;
  if (!aggregation_) aggregation_ = std::make_unique<Aggregation>();
  setup_kept_ = aggregation_->two_level.import_setup(state);
  setup_age_ = state.age;
  base_iterations_ = state.base_iterations;
  last_iterations_ = state.last_iterations;
}

PcgResult PressureSolver::solve(const SparseRows& matrix, const std::vector<double>& rhs,
                                std::vector<double>& x, double tolerance, int max_iterations,
                                const SparseRows* hierarchy_matrix) {
  const int n = matrix.rows();
  x.resize(n, 0.0);
  if (n == 0) {
    PcgResult empty;
    empty.converged = true;
    return empty;
  }
  if (preconditioner_ == Preconditioner::incomplete_cholesky) {
    return solve_incomplete_cholesky(matrix, rhs, x, tolerance, max_iterations);
  }
  const Preconditioner chosen = preconditioner_for(n);
  if (chosen != Preconditioner::aggregation) setup_kept_ = false;
  if (chosen == Preconditioner::aggregation) {
    if (!aggregation_) aggregation_ = std::make_unique<Aggregation>();
    const auto setup_start = StageClock::now();
    AggregationPreconditioner& two_level = aggregation_->two_level;
    const bool reused = setup_kept_ && row_keys_ && setup_age_ + 1 < setup_reuse_ &&
                        last_iterations_ <= base_iterations_ + kSetupReuseMargin &&
                        two_level.reuse(matrix, *row_keys_);
    if (reused) {
      ++setup_age_;
    } else {
      setup_kept_ = two_level.setup(matrix) && row_keys_ && setup_reuse_ > 1;
      if (setup_kept_) two_level.remember_keys(*row_keys_, key_count_);
      setup_age_ = 0;
    }
    const double setup_seconds = seconds_since(setup_start);
    PcgResult result =
        conjugate_gradients(matrix, rhs, x, tolerance, max_iterations, work_, upper(), nullptr,
                            [&](const std::vector<double>& r, std::vector<double>& z) {
                              return aggregation_->two_level.apply(r, z, kBlock, work_.partial);
                            });
    if (!reused) base_iterations_ = result.iterations;
    last_iterations_ = result.iterations;
    result.setup_seconds = setup_seconds;
    return result;
  }
  if (chosen == Preconditioner::amg) {
    if (!amg_) amg_ = std::make_unique<Amg>();
    const auto setup_start = StageClock::now();
    amg_->cycle.setup(hierarchy_matrix ? *hierarchy_matrix : matrix);
    const double setup_seconds = seconds_since(setup_start);
    PcgResult result =
        conjugate_gradients(matrix, rhs, x, tolerance, max_iterations, work_, upper(), nullptr,
                            [&](const std::vector<double>& r, std::vector<double>& z) {
                              amg_->cycle.apply(r, z);
                              return dot(r, z, work_.partial);
                            });
    result.setup_seconds = setup_seconds;
    return result;
  }
  invert_diagonal(matrix, inverse_diagonal_);
  const std::vector<double>& inverse_diagonal = inverse_diagonal_;
  return conjugate_gradients(matrix, rhs, x, tolerance, max_iterations, work_, upper(),
                             &inverse_diagonal,
                             [&](const std::vector<double>& r, std::vector<double>& z) {
                               const int size = static_cast<int>(r.size());
                               z.resize(size);
#pragma omp parallel for schedule(static) if (size >= 4096)
                               for (int i = 0; i < size; ++i) z[i] = inverse_diagonal[i] * r[i];
                               return dot(r, z, work_.partial);
                             });
}

void invert_diagonal(const SparseRows& matrix, std::vector<double>& inverse) {
  const int n = matrix.rows();
  inverse.resize(n);
#pragma omp parallel for schedule(static) if (n >= 4096)
  for (int i = 0; i < n; ++i) {
    double diagonal = 0.0;
    if (matrix.diagonal_first) {
      // The same value as the sum below: the other entries of the column are zeros.
      diagonal = matrix.offset[i + 1] > matrix.offset[i] ? matrix.value[matrix.offset[i]] : 0.0;
    } else {
      for (std::int64_t k = matrix.offset[i]; k < matrix.offset[i + 1]; ++k) {
        if (matrix.column[k] == i) diagonal += matrix.value[k];
      }
    }
    inverse[i] = diagonal > 0.0 ? 1.0 / diagonal : 1.0;
  }
}

void multiply(const SparseRows& matrix, const std::vector<double>& x, std::vector<double>& y,
              bool single_precision) {
  const int n = matrix.rows();
  y.resize(n);
  CgWork work;
  const RowView view = row_view(matrix, work, single_precision);
  const int blocks = (n + kBlock - 1) / kBlock;
#pragma omp parallel for schedule(static) if (blocks >= 4)
  for (int block = 0; block < blocks; ++block) {
    multiply_rows(view, x.data(), block * kBlock, std::min(n, (block + 1) * kBlock), y.data());
  }
}

PcgResult solve_pcg(const SparseRows& matrix, const std::vector<double>& rhs,
                    std::vector<double>& x, double tolerance, int max_iterations,
                    Preconditioner preconditioner) {
  PressureSolver solver(preconditioner);
  return solver.solve(matrix, rhs, x, tolerance, max_iterations);
}

}  // namespace cosim::mps
