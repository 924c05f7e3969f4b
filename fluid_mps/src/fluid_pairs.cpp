// The pair list of the fluid step and the internal particle order: one search kept over steps
// with a skin, particles reordered along its cells for memory locality, and the pairs within
// the stage radii at the current positions.
#include <algorithm>
#include <cmath>
#include <limits>
#ifdef __SSE2__
#include <emmintrin.h>
#endif

#include "cosim/fluid_mps/boundaries.hpp"
#include "cosim/fluid_mps/fluid_system.hpp"
#include "particle_loops.hpp"

// Loops run in parallel from 4096 items on: under that the OpenMP fork/join costs more than the
// work, and oversubscribed CI cores make it far worse.
namespace cosim::mps {
namespace {
const double kNotComputed = std::numeric_limits<double>::quiet_NaN();
}  // namespace

void FluidSystem::gather_state() {
  const int n = particle_count();
  if (static_cast<int>(order_.size()) != n) {
    order_.resize(n);
    rank_.resize(n);
    for (int i = 0; i < n; ++i) order_[i] = rank_[i] = i;
  }
  x_.resize(n);
  u_.resize(n);
  acceleration_.resize(n);
  p_.resize(n);
  kind_.resize(n);
#pragma omp parallel for schedule(static) if (n >= 4096)
  for (int k = 0; k < n; ++k) {
    const int i = order_[k];
    x_[k] = is_inactive(kinds_[i]) ? parked_position(i) : positions_[i];
    u_[k] = velocities_[i];
    acceleration_[k] = external_accelerations_[i];
    p_[k] = pressures_[i];
    kind_[k] = kinds_[i];
  }
}

// r*, u*, p and n* of the step become the public state; positions and velocities of inactive
// particles stay as they were set.
void FluidSystem::scatter_state() {
  const int n = particle_count();
  ++state_generation_;
  number_densities_.resize(n);
#pragma omp parallel for schedule(static) if (n >= 4096)
  for (int k = 0; k < n; ++k) {
    const int i = order_[k];
    if (!is_inactive(kind_[k])) {  // an inactive particle keeps the position it was given
      positions_[i] = position_star_[k];
      velocities_[i] = velocity_star_[k];
    }
    pressures_[i] = pressure_[k];
    number_densities_[i] = kind_[k] == ParticleKind::dummy ? kNotComputed : density_star_[k];
  }
}

void FluidSystem::update_neighbours(const std::vector<Eigen::Vector3d>& x, StepReport& report,
                                    bool reorder) {
  const MpsParameters& p = parameters_;
  const int n = particle_count();
  struct Book {  // the search's wall time into the report, however the function returns
    StageClock::time_point start;
    double& into;
    ~Book() { into += seconds_since(start); }
  } book{StageClock::now(), report.stage_seconds.search};
  const double skin = kSkinOverL0 * p.particle_spacing;
  // Two particles that each moved less than half the skin are still listed if now in reach.
  if (neighbours_valid_ && static_cast<int>(search_positions_.size()) == n) {
    double largest_move2 = 0.0;
#pragma omp parallel for schedule(static) reduction(max : largest_move2) if (n >= 4096)
    for (int k = 0; k < n; ++k) {
      if (is_inactive(kind_[k])) continue;
      largest_move2 =
          std::max(largest_move2, p.periodic.wrap(x[k] - search_positions_[k]).squaredNorm());
    }
    if (4.0 * largest_move2 < skin * skin) return;
  }
  const double list_radius = largest_influence_radius(p) + skin;
  const bool any_inactive = std::any_of(kind_.begin(), kind_.end(), is_inactive);
  auto grid_at = [&](const std::vector<Eigen::Vector3d>& at) {
    include_.clear();
    if (any_inactive) {
      include_.resize(n);
      for (int k = 0; k < n; ++k) include_[k] = is_inactive(kind_[k]) ? 0 : 1;
    }
    const std::vector<char>* included = any_inactive ? &include_ : nullptr;
    NeighbourGrid grid(p.dimension, bounding_box(at, p.dimension, list_radius, included),
                       list_radius, p.periodic);
    grid.build(at, included);
    return grid;
  };
  NeighbourGrid grid = grid_at(x);
  if (reorder) {
    // Cell order, the inactive particles (out of every cell) last.
    std::vector<int> order;
    order.reserve(n);
    for (const int k : grid.cell_order()) order.push_back(order_[k]);
    for (int k = 0; k < n; ++k) {
      if (any_inactive && !include_[k]) order.push_back(order_[k]);
    }
    order_ = std::move(order);
    for (int k = 0; k < n; ++k) rank_[order_[k]] = k;
    gather_state();  // x is x_, now in the new order
    grid = grid_at(x);
  }
  // Dummy particles get no row of their own: no stage reads one (they carry no pressure, take no
  // explicit or collision step, and are only partners of the walls' and the fluid's rows), so
  // their own number density is not computed either (number_densities(): NaN).
  own_row_.resize(n);
  bool any_dummy = false;
  for (int k = 0; k < n; ++k) {
    own_row_[k] = kind_[k] == ParticleKind::dummy ? 0 : 1;
    any_dummy = any_dummy || own_row_[k] == 0;
  }
  grid.neighbours_by_key(x, list_radius, order_, neighbours_, any_dummy ? &own_row_ : nullptr,
                         &search_work_);
  near_.offset = neighbours_.offset;
  near_.index.resize(neighbours_.pair_count());
  near_.distance.resize(neighbours_.pair_count());
  near_end_.resize(static_cast<std::size_t>(n));
  search_positions_ = x;
  neighbours_valid_ = true;
  ++report.neighbour_searches;
}

// Branch-free: every listed partner is written to the next slot (the arrays have room for the
// whole listed row), the slot kept only if in reach, with r^2; then the square roots of the kept
// ones in a second pass, two at a time. Both passes give the bits of the plain loop (the same r^2
// expression, and a square root is correctly rounded either way).
std::int64_t FluidSystem::find_row(int i, const std::vector<Eigen::Vector3d>& x, double cutoff2,
                                   int* index, double* distance) const {
  const PeriodicBoundary& periodic = parameters_.periodic;
  const Eigen::Vector3d xi = x[i];
  const std::int64_t begin = neighbours_.offset[i], end = neighbours_.offset[i + 1];
  const int* listed = neighbours_.index.data() + begin;
  const std::int64_t length = end - begin;
  std::int64_t slot = 0;
  if (periodic.enabled) {
    for (std::int64_t k = 0; k < length; ++k) {
      const int j = listed[k];
      const double r2 = periodic.wrap(x[j] - xi).squaredNorm();
      index[slot] = j;
      distance[slot] = r2;
      slot += static_cast<std::int64_t>(r2 <= cutoff2);
    }
  } else {
    for (std::int64_t k = 0; k < length; ++k) {
      const int j = listed[k];
      const double r2 = (x[j] - xi).squaredNorm();
      index[slot] = j;
      distance[slot] = r2;
      slot += static_cast<std::int64_t>(r2 <= cutoff2);
    }
  }
  std::int64_t k = 0;
#ifdef __SSE2__
  for (; k + 2 <= slot; k += 2) {
    _mm_storeu_pd(distance + k, _mm_sqrt_pd(_mm_loadu_pd(distance + k)));
  }
#endif
  for (; k < slot; ++k) distance[k] = std::sqrt(distance[k]);
  return slot;
}

void FluidSystem::find_near_row(int i, const std::vector<Eigen::Vector3d>& x, double cutoff2,
                                bool tail) {
  const std::int64_t begin = near_.offset[i], end = near_.offset[i + 1];
  int* index = near_.index.data();
  double* distance = near_.distance.data();
  std::int64_t slot = begin + find_row(i, x, cutoff2, index + begin, distance + begin);
  near_end_[i] = slot;
  if (!tail) return;
  for (; slot < end; ++slot) {
    index[slot] = i;
    distance[slot] = std::numeric_limits<double>::infinity();
  }
}

void FluidSystem::find_near_pairs(const std::vector<Eigen::Vector3d>& x, double cutoff) {
  const MpsParameters& p = parameters_;
  const int n = particle_count();
  const bool masked = !p.partitions.empty();
  const double cutoff2 = near_cutoff2(cutoff);
  near_.radius = cutoff;
#pragma omp parallel for schedule(dynamic, kParticleChunk) if (n >= 4096)
  for (int i = 0; i < n; ++i) find_near_row(i, x, cutoff2, masked);
  // Thin partitions (seed 001 section 2.2(1)) cut pairs at x: infinite distance.
  mask_partition_crossings(near_, x, p.partitions, p.periodic, &kind_);
}

}  // namespace cosim::mps
