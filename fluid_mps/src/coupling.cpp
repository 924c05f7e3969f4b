// Coupling hooks of FluidSystem: velocity sampling, point forces, momentum.
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>

#include <omp.h>

#include "cosim/fluid_mps/fluid_system.hpp"
#include "cosim/fluid_mps/neighbour_grid.hpp"

namespace cosim::mps {
namespace {

// Fluid particles within `radius` of each point: point q's group is index[offset[q] ..
// offset[q + 1]), in increasing particle index.
struct PointGroups {
  std::vector<std::int64_t> offset;
  std::vector<int> index;
  std::size_t size(std::size_t q) const {
    return static_cast<std::size_t>(offset[q + 1] - offset[q]);
  }
};

// The groups, from the kept grid (FluidSystem::point_grid). Each thread queries a contiguous
// range of points into its own buffer, joined in point order: no allocation per group (the
// groups' own vectors, allocated and freed by different threads, kept two threads slower than
// one).
template <class Grid>
PointGroups groups_within(const Grid& near, const std::vector<Eigen::Vector3d>& points,
                          double radius) {
  const int count = static_cast<int>(points.size());
  PointGroups groups;
  groups.offset.assign(points.size() + 1, 0);
  if (points.empty() || near.inside.empty()) return groups;
  const int team = count >= 64 ? std::max(1, omp_get_max_threads()) : 1;
  std::vector<std::vector<int>> found_by_thread(team);
#pragma omp parallel num_threads(team)
  {
    const int thread = omp_get_thread_num(), threads = omp_get_num_threads();
    const int first = static_cast<int>(static_cast<std::int64_t>(count) * thread / threads);
    const int last = static_cast<int>(static_cast<std::int64_t>(count) * (thread + 1) / threads);
    std::vector<int>& mine = found_by_thread[thread];
    std::vector<int> found;
    for (int q = first; q < last; ++q) {
      near.grid->query(near.at, points[q], radius, found);
      std::sort(found.begin(), found.end());  // grid entries in index order: particles too
      for (const int k : found) mine.push_back(near.inside[k]);
      groups.offset[q + 1] = static_cast<std::int64_t>(found.size());
    }
#pragma omp barrier
#pragma omp single
    {
      for (int q = 0; q < count; ++q) groups.offset[q + 1] += groups.offset[q];
      groups.index.resize(static_cast<std::size_t>(groups.offset[count]));
    }
    std::copy(mine.begin(), mine.end(), groups.index.begin() + groups.offset[first]);
  }
  return groups;
}

}  // namespace

// One cell grid over the fluid particles within reach of the points' bounding box (copied out in
// index order): walls, dummies, the parked pool and the water far from the points (a plant
// field, a log usually covers a small part of the domain) never enter it. A periodic run keeps
// the whole period (the seam). The box is padded by the radius, so that points moved a little
// (a plant's nodes between its samples and its forces) still find the grid complete; the groups
// are all particles within the radius, in index order, whatever grid finds them.
const FluidSystem::PointGrid& FluidSystem::point_grid(const std::vector<Eigen::Vector3d>& points,
                                                      double radius) const {
  if (!(radius > 0.0)) throw std::invalid_argument("sampling radius must be positive");
  PointGrid& near = point_grid_;
  if (points.empty()) return near;
  const MpsParameters& p = parameters_;
  Eigen::AlignedBox3d span(points.front());
  for (const auto& x : points) span.extend(x);
  const bool kept =
      near.generation == state_generation_ && near.radius == radius && near.reach.contains(span);
  if (kept) return near;
  near.generation = state_generation_;
  near.radius = radius;
  // The points' box padded by the radius; the particles are collected in that box padded by the
  // radius again, so points anywhere in near.reach have their whole disc in `reach`.
  near.reach = span;
  near.reach.min().array() -= radius;
  near.reach.max().array() += radius;
  Eigen::AlignedBox3d reach = near.reach;
  reach.min().array() -= radius;
  reach.max().array() += radius;
  near.inside.clear();
  near.at.clear();
  near.grid.reset();
  for (int i = 0; i < static_cast<int>(positions_.size()); ++i) {
    if (kinds_[i] != ParticleKind::fluid) continue;
    Eigen::Vector3d x = positions_[i];
    if (p.periodic.enabled) x.x() = reach.min().x();  // any x is within reach across the seam
    if (p.dimension == 2) x.z() = reach.min().z();
    if (!reach.contains(x)) continue;
    near.inside.push_back(i);
    near.at.push_back(positions_[i]);
  }
  if (near.inside.empty()) return near;
  double cell = std::max(radius, 2.0 * p.particle_spacing);
  // Periodic runs: at least three cells per period; query() then reaches over several cells.
  if (p.periodic.enabled) cell = std::min(cell, p.periodic.length() / 3.0);
  near.grid.emplace(p.dimension, bounding_box(near.at, p.dimension, cell), cell, p.periodic);
  near.grid->build(near.at);
  return near;
}

std::vector<std::vector<int>> FluidSystem::fluid_particles_near(
    const std::vector<Eigen::Vector3d>& points, double radius) const {
  const PointGroups groups = groups_within(point_grid(points, radius), points, radius);
  std::vector<std::vector<int>> result(points.size());
  for (std::size_t q = 0; q < points.size(); ++q) {
    result[q].assign(groups.index.begin() + groups.offset[q],
                     groups.index.begin() + groups.offset[q + 1]);
  }
  return result;
}

std::vector<Eigen::Vector3d> FluidSystem::sample_velocity(
    const std::vector<Eigen::Vector3d>& points, double radius,
    std::vector<double>* water_fraction) const {
  const auto groups = groups_within(point_grid(points, radius), points, radius);
  // Particles of a full lattice centred on a particle, within the radius (itself included).
  const double full =
      fill_lattice_sums(parameters_, radius / parameters_.particle_spacing).neighbour_count + 1.0;
  std::vector<Eigen::Vector3d> velocity(points.size(), Eigen::Vector3d::Zero());
  if (water_fraction) water_fraction->assign(points.size(), 0.0);
  for (std::size_t q = 0; q < points.size(); ++q) {
    const std::size_t size = groups.size(q);
    if (size == 0) continue;
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (std::int64_t k = groups.offset[q]; k < groups.offset[q + 1]; ++k) {
      sum += velocities_[groups.index[k]];
    }
    velocity[q] = sum / static_cast<double>(size);
    if (water_fraction) {
      (*water_fraction)[q] = std::clamp(static_cast<double>(size) / full, 0.0, 1.0);
    }
  }
  return velocity;
}

ForceDelivery FluidSystem::set_point_forces(const std::vector<Eigen::Vector3d>& points,
                                            const std::vector<Eigen::Vector3d>& forces,
                                            double radius) {
  return set_point_forces({{points, forces}}, radius);
}

ForceDelivery FluidSystem::set_point_forces(
    const std::vector<std::pair<std::vector<Eigen::Vector3d>, std::vector<Eigen::Vector3d>>>&
        point_forces,
    double radius) {
  std::fill(external_accelerations_.begin(), external_accelerations_.end(),
            Eigen::Vector3d::Zero());
  ForceDelivery delivery;
  for (const auto& [points, forces] : point_forces) {
    if (points.size() != forces.size()) {
      throw std::invalid_argument("set_point_forces: points and forces differ in size");
    }
    if (points.empty()) continue;
    const auto groups = groups_within(point_grid(points, radius), points, radius);
    // Serial accumulation in point order: deterministic.
    for (std::size_t q = 0; q < points.size(); ++q) {
      const std::size_t size = groups.size(q);
      if (size == 0) {
        ++delivery.undelivered_points;
        delivery.undelivered_force += forces[q];
        continue;
      }
      const Eigen::Vector3d acceleration = forces[q] / (particle_mass_ * static_cast<double>(size));
      for (std::int64_t k = groups.offset[q]; k < groups.offset[q + 1]; ++k) {
        external_accelerations_[groups.index[k]] += acceleration;
      }
    }
  }
  return delivery;
}

void FluidSystem::sample_surface(const std::vector<Eigen::Vector3d>& points, double radius,
                                 std::vector<double>& surface) const {
  if (!(radius > 0.0)) throw std::invalid_argument("sampling radius must be positive");
  const bool planar = parameters_.dimension == 2;
  const int vertical = planar ? 1 : 2;
  const double l0 = parameters_.particle_spacing;
  const auto& periodic = parameters_.periodic;
  constexpr double kNoWater = -std::numeric_limits<double>::infinity();
  surface.assign(points.size(), kNoWater);
  // Horizontal coordinates of a position: (x, 0) in 2D, (x, y) in 3D.
  auto horizontal = [&](const Eigen::Vector3d& x) {
    return Eigen::Vector2d(periodic.fold(x.x()), planar ? 0.0 : x.y());
  };
  // Both passes over the particles in parallel: minima and maxima are exact in any order.
  const int n = particle_count();
  const bool parallel = n >= 4096;
  Eigen::AlignedBox2d box;
#pragma omp parallel if (parallel)
  {
    Eigen::AlignedBox2d own;
#pragma omp for schedule(static) nowait
    for (int i = 0; i < n; ++i) {
      if (kinds_[i] == ParticleKind::fluid) own.extend(horizontal(positions_[i]));
    }
#pragma omp critical
    box.extend(own);
  }
  if (box.isEmpty() || points.empty()) return;
  if (periodic.enabled) {
    box.min().x() = periodic.x_min;
    box.max().x() = periodic.x_max;
  }
  // Highest fluid particle per column l0 wide, then the mean over the wet columns within the
  // radius of each point (a lone splashed particle moves it by l0 / columns, not by its height;
  // across the seam of a periodic run; the drop of a stepped period is not applied).
  const Eigen::Vector2d origin = box.min();
  const int nx = std::max(1, static_cast<int>(std::ceil((box.max().x() - origin.x()) / l0)));
  const int ny = planar ? 1 : static_cast<int>((box.max().y() - origin.y()) / l0) + 1;
  const std::size_t columns_count = static_cast<std::size_t>(nx) * ny;
  std::vector<double> top(columns_count, kNoWater);
#pragma omp parallel if (parallel)
  {
    std::vector<double> own(columns_count, kNoWater);
#pragma omp for schedule(static) nowait
    for (int i = 0; i < n; ++i) {
      if (kinds_[i] != ParticleKind::fluid) continue;
      const Eigen::Vector2d h = horizontal(positions_[i]);
      const int cx = std::clamp(static_cast<int>((h.x() - origin.x()) / l0), 0, nx - 1);
      const int cy = std::clamp(static_cast<int>((h.y() - origin.y()) / l0), 0, ny - 1);
      double& t = own[static_cast<std::size_t>(cy) * nx + cx];
      t = std::max(t, positions_[i][vertical]);
    }
#pragma omp critical
    for (std::size_t column = 0; column < columns_count; ++column) {
      top[column] = std::max(top[column], own[column]);
    }
  }
  const int reach = static_cast<int>(std::ceil(radius / l0)) + 1;
  const int reach_y = planar ? 0 : reach;
  for (std::size_t q = 0; q < points.size(); ++q) {
    const Eigen::Vector2d p = horizontal(points[q]);
    const int cx = static_cast<int>(std::floor((p.x() - origin.x()) / l0));
    const int cy = static_cast<int>(std::floor((p.y() - origin.y()) / l0));
    double top_sum = 0.0;
    int columns = 0;
    for (int dy = -reach_y; dy <= reach_y; ++dy) {
      for (int dx = -reach; dx <= reach; ++dx) {
        const int y = cy + dy;
        int x = cx + dx;
        if (periodic.enabled) x = ((x % nx) + nx) % nx;
        if (x < 0 || x >= nx || y < 0 || y >= ny) continue;
        // Distance from the point to the nearest edge of the column.
        const double gap_x =
            std::max(0.0, std::abs(origin.x() + (cx + dx + 0.5) * l0 - p.x()) - 0.5 * l0);
        const double gap_y =
            planar ? 0.0 : std::max(0.0, std::abs(origin.y() + (y + 0.5) * l0 - p.y()) - 0.5 * l0);
        if (gap_x * gap_x + gap_y * gap_y > radius * radius) continue;
        const double column_top = top[static_cast<std::size_t>(y) * nx + x];
        if (column_top == kNoWater) continue;
        top_sum += column_top;
        ++columns;
      }
    }
    if (columns > 0) surface[q] = top_sum / columns + 0.5 * l0;
  }
}

Eigen::Vector3d FluidSystem::total_fluid_momentum() const {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (int i = 0; i < particle_count(); ++i) {
    if (kinds_[i] == ParticleKind::fluid) sum += velocities_[i];
  }
  return particle_mass_ * sum;
}

}  // namespace cosim::mps
