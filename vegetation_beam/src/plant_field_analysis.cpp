// Plant-to-plant contact, energies, static solve and linear natural frequencies.
#include <Eigen/Eigenvalues>
#include <Eigen/QR>
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <string>

#include <omp.h>

#include "beam_elements.hpp"
#include "cosim/vegetation_beam/banded_matrix.hpp"
#include "cosim/vegetation_beam/plant_field.hpp"
#include "newmark_constants.hpp"

namespace cosim::vegetation {
namespace {

// Cell key of a uniform grid; 21 bits per axis, wrapping far away (the distance test removes
// any false neighbour a wrap produces).
std::uint64_t cell_key(std::int64_t ix, std::int64_t iy, std::int64_t iz) {
  constexpr std::uint64_t mask = (1u << 21) - 1;
  return (static_cast<std::uint64_t>(ix) & mask) | ((static_cast<std::uint64_t>(iy) & mask) << 21) |
         ((static_cast<std::uint64_t>(iz) & mask) << 42);
}

// From this many nodes the close pairs are found on all threads (each a range of nodes).
constexpr std::size_t kClosePairsSideBySide = 2048;

// The run [begin, end) of each cell key in a key-sorted list, by open addressing (linear
// probing in a table at least twice the list's size): no allocation per cell, as a node-based
// map needs, at every rebuild of the candidates.
class CellRuns {
 public:
  explicit CellRuns(const std::vector<std::pair<std::uint64_t, int>>& keyed) {
    std::size_t capacity = 16;
    while (capacity < 2 * keyed.size()) capacity *= 2;
    shift_ = 64 - std::countr_zero(capacity);
    slots_.assign(capacity, Slot{});
    for (std::size_t k = 0; k < keyed.size();) {
      std::size_t end = k + 1;
      while (end < keyed.size() && keyed[end].first == keyed[k].first) ++end;
      std::size_t slot = home(keyed[k].first);
      while (slots_[slot].key != kEmpty) slot = (slot + 1) & (capacity - 1);
      slots_[slot] = Slot{keyed[k].first, k, end};
      k = end;
    }
  }
  std::pair<std::size_t, std::size_t> find(std::uint64_t key) const {
    for (std::size_t slot = home(key);; slot = (slot + 1) & (slots_.size() - 1)) {
      if (slots_[slot].key == key) return {slots_[slot].begin, slots_[slot].end};
      if (slots_[slot].key == kEmpty) return {0, 0};
    }
  }

 private:
  // cell_key uses 63 bits: the all-ones key marks an empty slot.
  static constexpr std::uint64_t kEmpty = ~std::uint64_t{0};
  struct Slot {
    std::uint64_t key = kEmpty;
    std::size_t begin = 0, end = 0;
  };
  std::size_t home(std::uint64_t key) const {
    return static_cast<std::size_t>((key * 0x9E3779B97F4A7C15ull) >> shift_);  // Fibonacci hash
  }
  int shift_ = 0;
  std::vector<Slot> slots_;
};

}  // namespace

void PlantField::update_contact_candidates() {
  update_contact_candidates(positions_);
}

double PlantField::largest_move(std::span<const Eigen::Vector3d> x,
                                const std::vector<Eigen::Vector3d>& from) {
  double moved = 0;
  for (std::size_t k = 0; k < x.size(); ++k)
    moved = std::max(moved, (x[k] - from[k]).squaredNorm());
  return std::sqrt(moved);
}

void PlantField::update_contact_candidates(std::span<const Eigen::Vector3d> x) {
  if (candidates_valid_) {
    // The list holds every pair within reach + margin; it stays complete while no node has
    // moved more than half the margin.
    if (largest_move(x, candidate_positions_) < 0.5 * contact_margin_) return;
  }
  candidate_positions_.assign(x.begin(), x.end());
  candidates_valid_ = true;
  contact_candidates_.clear();
  for_each_close_pair(candidate_positions_, contact_margin_, [&](int a, int b) {
    contact_candidates_.emplace_back(a, b);
    return true;
  });
}

void PlantField::for_each_close_pair(const std::vector<Eigen::Vector3d>& x, double margin,
                                     const std::function<bool(int, int)>& visit) const {
  const std::size_t n = x.size();
  double max_radius = 0;
  for (double r : contact_radius_) max_radius = std::max(max_radius, r);
  const double cell = 2 * max_radius + margin;
  std::vector<std::pair<std::uint64_t, int>> keyed(n);
  std::vector<Eigen::Vector3i> cells(n);
  for (std::size_t k = 0; k < n; ++k) {
    const Eigen::Vector3d scaled = x[k] / cell;
    cells[k] = Eigen::Vector3i(static_cast<int>(std::floor(scaled.x())),
                               static_cast<int>(std::floor(scaled.y())),
                               static_cast<int>(std::floor(scaled.z())));
    keyed[k] = {cell_key(cells[k].x(), cells[k].y(), cells[k].z()), static_cast<int>(k)};
  }
  std::sort(keyed.begin(), keyed.end());
  // Each occupied cell's run in `keyed`, found by hash: most of a node's 27 neighbour cells are
  // empty, and a binary search over all nodes for each took a fifth of a reed field's time.
  const CellRuns runs(keyed);
  // Each thread finds the pairs of a contiguous range of nodes a; visited in node order after.
  const int team = n >= kClosePairsSideBySide ? std::max(1, omp_get_max_threads()) : 1;
  std::vector<std::vector<std::pair<int, int>>> found(team);
#pragma omp parallel num_threads(team)
  {
    const int thread = omp_get_thread_num(), threads = omp_get_num_threads();
    std::vector<std::pair<int, int>>& mine = found[thread];
    const std::size_t first = n * thread / threads, last = n * (thread + 1) / threads;
    for (std::size_t a = first; a < last; ++a) {
      for (int dx = -1; dx <= 1; ++dx) {
        for (int dy = -1; dy <= 1; ++dy) {
          for (int dz = -1; dz <= 1; ++dz) {
            const std::uint64_t key =
                cell_key(cells[a].x() + dx, cells[a].y() + dy, cells[a].z() + dz);
            const auto [run_begin, run_end] = runs.find(key);
            for (std::size_t t = run_begin; t < run_end; ++t) {
              const std::size_t b = static_cast<std::size_t>(keyed[t].second);
              if (b <= a || node_plant_[a] == node_plant_[b]) continue;
              const bool a_base = plants_[node_plant_[a]].first == static_cast<int>(a);
              const bool b_base = plants_[node_plant_[b]].first == static_cast<int>(b);
              if (a_base && b_base) continue;  // two clamped nodes never move
              const double reach = contact_radius_[a] + contact_radius_[b] + margin;
              if ((x[a] - x[b]).squaredNorm() < reach * reach)
                mine.emplace_back(static_cast<int>(a), static_cast<int>(b));
            }
          }
        }
      }
    }
  }
  for (const auto& part : found) {
    for (const auto& [a, b] : part) {
      if (!visit(a, b)) return;
    }
  }
}

void PlantField::compute_contact_forces(const std::vector<Eigen::Vector3d>& x,
                                        const std::vector<Eigen::Vector3d>& v,
                                        bool decide_active_pairs) {
  if (decide_active_pairs) {
    clear_contact_state();
  } else {
    clear_contact_forces();
  }
  for (std::size_t pair = 0; pair < contact_candidates_.size(); ++pair) {
    const auto [a, b] = contact_candidates_[pair];
    const Eigen::Vector3d r = x[a] - x[b];
    const double distance = r.norm();
    const double reach = contact_radius_[a] + contact_radius_[b];
    // The set of touching pairs is fixed at the predictor of each sub-step: letting pairs
    // switch inside the Newton loop makes it cycle between the two sides of the contact edge.
    if (decide_active_pairs) contact_active_[pair] = distance < reach && distance > 0;
    if (!contact_active_[pair] || distance == 0) continue;
    if (decide_active_pairs) {
      plant_contact_pairs_[node_plant_[a]].push_back(static_cast<int>(pair));
      plant_contact_pairs_[node_plant_[b]].push_back(static_cast<int>(pair));
    }
    // Normal spring-dashpot of eq. 18-21; the tangential (friction) part of the seed is left
    // out.
    const Eigen::Vector3d e = r / distance;
    const double approach = (v[a] - v[b]).dot(e);
    const double normal = contact_stiffness_ * (reach - distance) - contact_damping_ * approach;
    const Eigen::Matrix3d along = e * e.transpose();
    for (const auto& [node, sign] : {std::pair{a, 1.0}, std::pair{b, -1.0}}) {
      contact_forces_[node] += sign * normal * e;
      // Only the node's own block goes into the Jacobian (plants are solved one at a time).
      contact_stiffness_blocks_[node] += contact_stiffness_ * along;
      contact_damping_blocks_[node] += contact_damping_ * along;
      contact_touched_nodes_.push_back(node);
      plant_in_contact_[node_plant_[node]] = 1;
    }
  }
}

void PlantField::clear_contact_forces() {
  for (int k : contact_touched_nodes_) {
    contact_forces_[k].setZero();
    contact_stiffness_blocks_[k].setZero();
    contact_damping_blocks_[k].setZero();
  }
  contact_touched_nodes_.clear();
  std::fill(plant_in_contact_.begin(), plant_in_contact_.end(), 0);
}

void PlantField::clear_contact_state() {
  clear_contact_forces();
  contact_active_.assign(contact_candidates_.size(), 0);
  plant_contact_pairs_.resize(plants_.size());
  for (auto& pairs : plant_contact_pairs_) pairs.clear();
}

void PlantField::refresh_contact_forces(int plant_index, double dt) {
  const Plant& plant = plants_[plant_index];
  for (int i = 1; i <= plant.links; ++i) contact_forces_[plant.first + i].setZero();
  // Velocity from the current trial position by the Newmark relations (eq. 22-23).
  const auto velocity = [&](int k) -> Eigen::Vector3d {
    if (plants_[node_plant_[k]].first == k) return Eigen::Vector3d::Zero();  // clamped base
    const Eigen::Vector3d acceleration =
        (positions_[k] - previous_positions_[k] - dt * previous_velocities_[k]) /
            (kBeta * dt * dt) -
        (0.5 / kBeta - 1.0) * previous_accelerations_[k];
    return previous_velocities_[k] +
           dt * ((1 - kGamma) * previous_accelerations_[k] + kGamma * acceleration);
  };
  for (int pair : plant_contact_pairs_[plant_index]) {
    const auto [a, b] = contact_candidates_[pair];
    const Eigen::Vector3d r = positions_[a] - positions_[b];
    const double distance = r.norm();
    if (distance == 0) continue;
    const Eigen::Vector3d e = r / distance;
    const double approach = (velocity(a) - velocity(b)).dot(e);
    const double normal =
        contact_stiffness_ * (contact_radius_[a] + contact_radius_[b] - distance) -
        contact_damping_ * approach;
    if (node_plant_[a] == plant_index && a != plant.first) contact_forces_[a] += normal * e;
    if (node_plant_[b] == plant_index && b != plant.first) contact_forces_[b] -= normal * e;
  }
}

double PlantField::kinetic_energy() const {
  double energy = 0;
  for (const Plant& plant : plants_)
    for (int i = 1; i <= plant.links; ++i)
      energy += 0.5 * node_mass_[plant.first + i] * velocities_[plant.first + i].squaredNorm();
  return energy;
}

double PlantField::elastic_energy() const {
  double energy = 0;
  BendingJoint joint;
  const Eigen::Vector3d zero = Eigen::Vector3d::Zero();
  const Eigen::Vector3d rates[3] = {zero, zero, zero};
  for (const Plant& plant : plants_) {
    const int first = plant.first;
    for (int i = 1; i <= plant.links; ++i) {
      energy += axial_link(positions_[first + i - 1], positions_[first + i], zero, zero,
                           plant.axial_spring, 0, plant.link_length)
                    .energy;
    }
    for (int j = 0; j < plant.links; ++j) {
      const Eigen::Vector3d nodes[3] = {j == 0 ? plant.ghost : positions_[first + j - 1],
                                        positions_[first + j], positions_[first + j + 1]};
      bending_joint(nodes, rates, (j == 0 ? 2.0 : 1.0) * plant.bending_spring, 0, false, joint);
      energy += joint.energy;
    }
  }
  if (parameters_.contact) {
    for (const auto& [a, b] : contact_candidates_) {
      const double overlap =
          contact_radius_[a] + contact_radius_[b] - (positions_[a] - positions_[b]).norm();
      if (overlap > 0) energy += 0.5 * contact_stiffness_ * overlap * overlap;
    }
  }
  return energy + bed_energy();
}

double PlantField::potential_energy() const {
  double energy = 0;
  for (std::size_t k = 0; k < positions_.size(); ++k)
    energy -= (body_forces_[k] + external_forces_[k]).dot(positions_[k] - initial_positions_[k]);
  return energy;
}

Eigen::Vector3d PlantField::tip_displacement(int plant) const {
  const Plant& p = plants_.at(plant);
  const int tip = p.first + p.links;
  return positions_[tip] - initial_positions_[tip];
}

StaticReport PlantField::solve_static(double tolerance, int max_iterations) {
  StaticReport report;
  const std::size_t n = positions_.size();
  std::fill(velocities_.begin(), velocities_.end(), Eigen::Vector3d::Zero());
  const std::vector<Eigen::Vector3d> still(n, Eigen::Vector3d::Zero());
  const bool contact = plants_may_touch();
  BandedMatrix jacobian;
  std::vector<double> static_correction;  // scratch of apply_newton_correction
  std::vector<char> converged(plants_.size(), 0);
  std::vector<double> last_correction(plants_.size(), 0.0);
  const auto fail = [&](int plant, int node, const std::string& what) {
    throw StabilityError("vegetation_beam: plant " + std::to_string(plant) + " node " +
                         std::to_string(node) + ": static solve: " + what);
  };
  for (report.iterations = 1; report.iterations <= max_iterations; ++report.iterations) {
    if (contact) {
      update_contact_candidates();
      compute_contact_forces(positions_, velocities_, true);
    }
    bool all_converged = true;
    report.max_correction = 0;
    for (int p = 0; p < plant_count(); ++p) {
      const Plant& plant = plants_[p];
      jacobian.resize(3 * plant.links, 8);
      compute_forces(p, positions_, still, still, contact, forces_, drag_, &jacobian, 1.0, 0.0);
      for (int i = 1; i <= plant.links; ++i) residual_[plant.first + i] = -forces_[plant.first + i];
      const Correction correction =
          apply_newton_correction(p, jacobian, residual_, true, static_correction);
      if (correction.singular)
        fail(p, correction.node,
             "singular stiffness (a load that buckles the plant, or a plant with no bending "
             "stiffness)");
      if (!std::isfinite(correction.largest))
        fail(p, correction.node, "Newton correction is not finite");
      last_correction[p] = correction.largest;
      report.max_correction =
          std::max(report.max_correction, correction.largest * plant.link_length);
      converged[p] = correction.largest <= tolerance;
      all_converged = all_converged && converged[p];
    }
    if (all_converged) break;
  }
  if (report.iterations > max_iterations) {
    NewtonOutcome worst;
    locate_largest_residual(converged, worst);
    std::ostringstream out;
    out.precision(3);
    out << "did not converge in " << max_iterations << " Newton iterations: residual "
        << worst.residual << " N is largest here, last correction " << last_correction[worst.plant]
        << " link lengths against " << tolerance
        << " (loads beyond a snap-through or buckling limit have no nearby equilibrium; start "
           "from a shape closer to it or lower the loads)";
    fail(worst.plant, worst.node, out.str());
  }
  accelerations_valid_ = false;
  return report;
}

void PlantField::linear_problem(int plant_index, Eigen::MatrixXd& stiffness_matrix,
                                Eigen::MatrixXd& mass) const {
  const Plant& plant = plants_.at(plant_index);
  const int dofs = 3 * plant.links;
  BandedMatrix stiffness;
  stiffness.resize(dofs, 8);
  std::vector<Eigen::Vector3d> force(positions_.size()), drag(positions_.size());
  const std::vector<Eigen::Vector3d> still(positions_.size(), Eigen::Vector3d::Zero());
  compute_forces(plant_index, positions_, still, still, false, force, drag, &stiffness, 1.0, 0.0);
  const Eigen::MatrixXd k = stiffness.to_dense();
  stiffness_matrix = 0.5 * (k + k.transpose());
  mass = Eigen::MatrixXd::Zero(dofs, dofs);
  for (int i = 1; i <= plant.links; ++i)
    for (int d = 0; d < 3; ++d)
      mass(3 * (i - 1) + d, 3 * (i - 1) + d) = node_mass_[plant.first + i];
}

std::vector<double> PlantField::linear_natural_frequencies(int plant_index, int count) const {
  Eigen::MatrixXd k, m;
  linear_problem(plant_index, k, m);
  Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> solver(k, m, Eigen::EigenvaluesOnly);
  std::vector<double> frequencies;
  for (int i = 0; i < k.rows() && static_cast<int>(frequencies.size()) < count; ++i) {
    const double f = std::sqrt(std::max(0.0, solver.eigenvalues()(i))) / (2 * std::numbers::pi);
    if (!frequencies.empty() && std::abs(f - frequencies.back()) <= 1e-6 * f) continue;
    frequencies.push_back(f);
  }
  return frequencies;
}

std::vector<LinearMode> PlantField::linear_modes(int plant_index, int count) const {
  Eigen::MatrixXd k, m;
  linear_problem(plant_index, k, m);
  Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> solver(k, m);
  const Plant& plant = plants_[plant_index];
  std::vector<LinearMode> modes;
  for (int i = 0; i < k.rows() && static_cast<int>(modes.size()) < count; ++i) {
    LinearMode mode;
    mode.frequency = std::sqrt(std::max(0.0, solver.eigenvalues()(i))) / (2 * std::numbers::pi);
    mode.shape.assign(plant.links + 1, Eigen::Vector3d::Zero());
    for (int node = 1; node <= plant.links; ++node)
      mode.shape[node] = solver.eigenvectors().col(i).segment<3>(3 * (node - 1));
    modes.push_back(std::move(mode));
  }
  return modes;
}

Eigen::Vector3d PlantField::set_mode_velocity(int plant_index, int mode,
                                              const Eigen::Vector3d& tip_velocity) {
  const Plant& plant = plants_.at(plant_index);
  if (mode < 1) throw std::invalid_argument("vegetation_beam: mode numbers start at 1");
  // Enough modes for `mode` distinct frequencies, each possibly a degenerate pair.
  const std::vector<LinearMode> modes =
      linear_modes(plant_index, std::min(3 * plant.links, 2 * mode + 1));
  std::vector<int> group;  // the modes sharing the mode-th distinct frequency
  int distinct = 0;
  double current = -1;
  for (int i = 0; i < static_cast<int>(modes.size()); ++i) {
    const double f = modes[i].frequency;
    if (current < 0 || std::abs(f - current) > 1e-6 * f) {
      ++distinct;
      current = f;
    }
    if (distinct == mode) group.push_back(i);
    if (distinct > mode) break;
  }
  if (group.empty())
    throw std::invalid_argument("vegetation_beam: plant " + std::to_string(plant_index) +
                                " has only " + std::to_string(distinct) + " distinct modes");
  // Least squares for the tip: tip_shapes * c = tip_velocity.
  Eigen::MatrixXd tip_shapes(3, static_cast<int>(group.size()));
  for (int j = 0; j < static_cast<int>(group.size()); ++j)
    tip_shapes.col(j) = modes[group[j]].shape[plant.links];
  const Eigen::VectorXd c = tip_shapes.colPivHouseholderQr().solve(tip_velocity);
  for (int node = 0; node <= plant.links; ++node) {
    Eigen::Vector3d v = Eigen::Vector3d::Zero();
    for (int j = 0; j < static_cast<int>(group.size()); ++j)
      v += c(j) * modes[group[j]].shape[node];
    velocities_[plant.first + node] = v;
  }
  accelerations_valid_ = false;
  return tip_shapes * c;
}

}  // namespace cosim::vegetation
