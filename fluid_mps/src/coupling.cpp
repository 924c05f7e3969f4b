// Coupling hooks of FluidSystem: velocity sampling, point forces, momentum.
#include <algorithm>
#include <stdexcept>

#include "cosim/fluid_mps/fluid_system.hpp"
#include "cosim/fluid_mps/neighbour_grid.hpp"

namespace cosim::mps {
namespace {

// Fluid particles within `radius` of each point, found with one cell grid.
std::vector<std::vector<int>> fluid_within(const MpsParameters& p,
                                           const std::vector<Eigen::Vector3d>& positions,
                                           const std::vector<ParticleKind>& kinds,
                                           const std::vector<Eigen::Vector3d>& points,
                                           double radius) {
  if (!(radius > 0.0)) throw std::invalid_argument("sampling radius must be positive");
  double cell = std::max(radius, 2.0 * p.particle_spacing);
  // Periodic runs: at least three cells per period; query() then reaches over several cells.
  if (p.periodic.enabled) cell = std::min(cell, p.periodic.length() / 3.0);
  NeighbourGrid grid(p.dimension, bounding_box(positions, p.dimension, cell), cell, p.periodic);
  grid.build(positions);
  std::vector<std::vector<int>> result(points.size());
  const int count = static_cast<int>(points.size());
#pragma omp parallel for schedule(dynamic, 16) if (count >= 64)
  for (int q = 0; q < count; ++q) {
    std::vector<int> found;
    grid.query(positions, points[q], radius, found);
    for (int j : found) {
      if (kinds[j] == ParticleKind::fluid) result[q].push_back(j);
    }
  }
  return result;
}

}  // namespace

std::vector<Eigen::Vector3d> FluidSystem::sample_velocity(
    const std::vector<Eigen::Vector3d>& points, double radius,
    std::vector<double>* water_fraction) const {
  const auto groups = fluid_within(parameters_, positions_, kinds_, points, radius);
  // Particles of a full lattice centred on a particle, within the radius (itself included).
  const double full =
      lattice_sums(parameters_.dimension, radius / parameters_.particle_spacing).neighbour_count +
      1.0;
  std::vector<Eigen::Vector3d> velocity(points.size(), Eigen::Vector3d::Zero());
  if (water_fraction) water_fraction->assign(points.size(), 0.0);
  for (std::size_t q = 0; q < points.size(); ++q) {
    const auto& group = groups[q];
    if (group.empty()) continue;
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (int j : group) sum += velocities_[j];
    velocity[q] = sum / static_cast<double>(group.size());
    if (water_fraction) {
      (*water_fraction)[q] = std::clamp(static_cast<double>(group.size()) / full, 0.0, 1.0);
    }
  }
  return velocity;
}

ForceDelivery FluidSystem::apply_point_forces(const std::vector<Eigen::Vector3d>& points,
                                              const std::vector<Eigen::Vector3d>& forces,
                                              double radius) {
  if (points.size() != forces.size()) {
    throw std::invalid_argument("apply_point_forces: points and forces differ in size");
  }
  const auto groups = fluid_within(parameters_, positions_, kinds_, points, radius);
  ForceDelivery delivery;
  // Serial accumulation in point order: deterministic.
  for (std::size_t q = 0; q < points.size(); ++q) {
    const auto& group = groups[q];
    if (group.empty()) {
      ++delivery.undelivered_points;
      delivery.undelivered_force += forces[q];
      continue;
    }
    const Eigen::Vector3d acceleration =
        forces[q] / (particle_mass_ * static_cast<double>(group.size()));
    for (int j : group) external_accelerations_[j] += acceleration;
  }
  return delivery;
}

Eigen::Vector3d FluidSystem::total_fluid_momentum() const {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (int i = 0; i < particle_count(); ++i) {
    if (kinds_[i] == ParticleKind::fluid) sum += velocities_[i];
  }
  return particle_mass_ * sum;
}

}  // namespace cosim::mps
