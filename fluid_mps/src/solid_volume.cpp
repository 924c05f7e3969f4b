// Solid volume in the fluid (FluidSystem::set_solid_volumes): the solid fraction phi at the fluid
// particles, from the solids' volumes spread with a normalised kernel.
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "cosim/fluid_mps/fluid_system.hpp"
#include "cosim/numerics/lucy_kernel.hpp"

namespace cosim::mps {

void FluidSystem::set_solid_volumes(std::vector<Eigen::Vector3d> points,
                                    std::vector<double> volumes, double radius) {
  if (points.size() != volumes.size()) {
    throw std::invalid_argument("set_solid_volumes: one volume per point");
  }
  if (!points.empty() && !(radius > 0.0)) {
    throw std::invalid_argument("set_solid_volumes: the spreading radius must be positive");
  }
  for (const double v : volumes) {
    if (!(v >= 0.0) || !std::isfinite(v)) {
      throw std::invalid_argument("set_solid_volumes: volumes must be finite and >= 0");
    }
  }
  solid_points_ = std::move(points);
  solid_volumes_ = std::move(volumes);
  solid_radius_ = radius;
}

void FluidSystem::update_solid_fractions(const std::vector<Eigen::Vector3d>& x) {
  const int n = particle_count();
  solid_fraction_.assign(static_cast<std::size_t>(n), 0.0);
  largest_solid_fraction_ = 0.0;
  if (solid_points_.empty()) return;
  const auto& periodic = parameters_.periodic;
  const int d = parameters_.dimension;
  const double reach2 = solid_radius_ * solid_radius_;
  double largest = 0.0;
  // Few solid points against many particles: each particle sums over all points (in point
  // order, so any thread count gives the same bits).
#pragma omp parallel for schedule(static) reduction(max : largest) if (n >= 4096)
  for (int i = 0; i < n; ++i) {
    if (!is_fluid(kinds_[i])) continue;
    double phi = 0.0;
    for (std::size_t e = 0; e < solid_points_.size(); ++e) {
      if (solid_volumes_[e] <= 0.0) continue;
      const double r2 = periodic.wrap(x[i] - solid_points_[e]).squaredNorm();
      if (r2 >= reach2) continue;
      phi += solid_volumes_[e] * numerics::lucy_kernel(std::sqrt(r2), solid_radius_, d);
    }
    largest = std::max(largest, phi);
    solid_fraction_[i] = std::min(phi, kMaximumSolidFraction);
  }
  largest_solid_fraction_ = largest;
}

}  // namespace cosim::mps
