// Stage 4 of the MPS step: the pressure Poisson equation assembled on the unknowns and solved.
#include <algorithm>
#include <cmath>

#include <omp.h>

#include "cosim/fluid_mps/fluid_system.hpp"
#include "cosim/fluid_mps/operators.hpp"
#include "step_constants.hpp"

namespace cosim::mps {

// 4. Pressure Poisson equation with the Laplacian model (seed 001 eq. (9)):
//    <lap p>_i - rho alpha p_i / dt^2 = -gamma rho / dt^2 (n*_i - n0) / n0,
// multiplied by -lambda n0 / (2d) so the matrix is symmetric positive definite:
//    sum_j w_ij (p_i - p_j) + c alpha p_i = c gamma (n*_i - n0) / n0,
//    c = lambda n0 rho / (2d dt^2);
// with the mixed source the right side is c (gamma (n^k_i - n0) / n0 - dt <div u*>_i).
void FluidSystem::assemble_pressure_equation(const StepConstants& c) {
  const MpsParameters& p = parameters_;
  const int m = static_cast<int>(unknown_particle_.size());
  const double scale = c.lambda * c.n0_l * p.density / (2.0 * c.d * c.dt * c.dt);
  assemble_laplacian_rows(c.re_l, scale * p.compressibility, matrix_, assembly_buffers_);
  rhs_.resize(m);
  solution_.resize(m);
#pragma omp parallel for schedule(static) if (m >= 4096)
  for (int row = 0; row < m; ++row) {
    const int i = unknown_particle_[row];
    // Target (1 - phi_i) n0 (set_solid_volumes); the row keeps the n0 scaling so the matrix
    // stays symmetric. The divergence part has no d phi / dt term: with solids, the density
    // error is what pushes the displaced water away.
    const double target = c.n0_n * (1.0 - phi_[i]);
    rhs_[row] = p.source_term == MpsParameters::SourceTerm::density
                    ? scale * p.pressure_relaxation * (density_star_[i] - target) / c.n0_n
                    : scale * (p.pressure_relaxation * (density_now_[i] - target) / c.n0_n -
                               c.dt * divergence_[i]);
    solution_[row] = p_[i];  // warm start from the previous step
  }
  if (pressure_solver_.uses_amg(m)) {
    // The multigrid hierarchy comes from the same equation with the short radius: a quarter of
    // the entries per row in 2D, so the set-up costs far less, and CG on the full matrix does
    // not care that its preconditioner approximates a slightly different Laplacian.
    const double hierarchy_scale = hierarchy_sums_.lambda_over_l0sq * p.particle_spacing *
                                   p.particle_spacing * hierarchy_sums_.n0 * p.density /
                                   (2.0 * c.d * c.dt * c.dt);
    assemble_laplacian_rows(hierarchy_radius(), hierarchy_scale * p.compressibility,
                            hierarchy_matrix_, hierarchy_buffers_);
  }
}

// Rows sum_j w_ij (p_i - p_j) + shift p_i of the unknowns (Laplacian model of radius `radius`):
// Dirichlet neighbours (free surface, p = 0) only add to the diagonal; dummy particles are left
// out. One pass over the pairs: each thread writes its contiguous share of the rows into its own
// buffer, and the buffers are copied into place once the row offsets are summed (on one thread
// the buffer becomes the matrix).
void FluidSystem::assemble_laplacian_rows(double radius, double diagonal_shift, SparseRows& matrix,
                                          std::vector<AssemblyBuffer>& buffers) {
  const NeighbourList& list = near_;
  const int m = static_cast<int>(unknown_particle_.size());
  fill(row_length_, static_cast<std::size_t>(m) + 1, std::int64_t{0});
  const int threads = m >= 4096 ? std::max(1, omp_get_max_threads()) : 1;
  if (static_cast<int>(buffers.size()) < threads) buffers.resize(threads);
  matrix.diagonal_first = true;  // below: the first slot, then zeros in its column
#pragma omp parallel num_threads(threads)
  {
    const int thread = omp_get_thread_num(), team = omp_get_num_threads();
    const int first = static_cast<int>(static_cast<std::int64_t>(m) * thread / team);
    const int last = static_cast<int>(static_cast<std::int64_t>(m) * (thread + 1) / team);
    AssemblyBuffer& buffer = buffers[thread];
    // Room for every pair of the share and its diagonals; the buffers only grow.
    std::int64_t room = 0;
    for (int row = first; row < last; ++row) {
      const int i = unknown_particle_[row];
      room += near_end_[i] - list.offset[i] + 1;
    }
    if (static_cast<std::int64_t>(buffer.column.size()) < room) {
      buffer.column.resize(room);
      buffer.value.resize(room);
    }
    int* const column = buffer.column.data();
    double* const value = buffer.value.data();
    std::int64_t used = 0;
    for (int row = first; row < last; ++row) {
      const int i = unknown_particle_[row];
      const std::int64_t diagonal_slot = used++;
      double diagonal = diagonal_shift;
      int rounded_away = 0;  // unknown partners inside the radius whose weight rounds to zero
      for (std::int64_t k = list.offset[i]; k < near_end_[i]; ++k) {
        const int j = list.index[k];
        if (kind_[j] == ParticleKind::dummy) continue;
        const double w = weight(list.distance[k], radius);
        if (w <= 0.0) {
          if (unknown_[j] >= 0 && list.distance[k] < radius) ++rounded_away;
          continue;
        }
        diagonal += w;
        if (unknown_[j] >= 0) {
          column[used] = unknown_[j];
          value[used] = -w;
          ++used;
        }
      }
      // Such a partner keeps a zero slot in the diagonal's column (the rows of the two-pass
      // assembly this replaced had them: the same matrix, so the same bits).
      for (int k = 0; k < rounded_away; ++k, ++used) {
        column[used] = row;
        value[used] = 0.0;
      }
      column[diagonal_slot] = row;
      value[diagonal_slot] = diagonal;
      row_length_[row + 1] = used - diagonal_slot;
    }
#pragma omp barrier
#pragma omp single
    {
      for (int row = 0; row < m; ++row) row_length_[row + 1] += row_length_[row];
      matrix.offset = row_length_;
      if (team == 1) {
        // One share holds every row in place: the buffer becomes the matrix (no copy; a 3D
        // step on one thread spent 3 % copying), and the matrix's storage the next buffer.
        matrix.column.swap(buffer.column);
        matrix.value.swap(buffer.value);
      }
      matrix.column.resize(row_length_[m]);
      matrix.value.resize(row_length_[m]);
    }
    if (team > 1) {
      std::copy(column, column + used, matrix.column.begin() + row_length_[first]);
      std::copy(value, value + used, matrix.value.begin() + row_length_[first]);
    }
  }
}

void FluidSystem::solve_pressure(StepReport& report) {
  const bool amg = pressure_solver_.uses_amg(matrix_.rows());
  row_keys_.resize(unknown_particle_.size());
  for (std::size_t row = 0; row < unknown_particle_.size(); ++row)
    row_keys_[row] = order_[unknown_particle_[row]];
  pressure_solver_.set_row_keys(&row_keys_, particle_count());
  const PcgResult pcg =
      pressure_solver_.solve(matrix_, rhs_, solution_, parameters_.pcg_tolerance,
                             parameters_.pcg_max_iterations, amg ? &hierarchy_matrix_ : nullptr);
  report.pcg_iterations = pcg.iterations;
  report.stage_seconds.pressure_setup = pcg.setup_seconds;
  report.pcg_residual = pcg.relative_residual;
  report.pcg_converged = pcg.converged;
  // Negative pressures are clamped to zero: MPS has no tension (standard practice).
  fill(pressure_, static_cast<std::size_t>(particle_count()), 0.0);
  for (std::size_t row = 0; row < unknown_particle_.size(); ++row) {
    pressure_[unknown_particle_[row]] = std::max(0.0, solution_[row]);
  }
}

}  // namespace cosim::mps
