// Scene builders of the open and periodic boundaries (boundaries.hpp).
#include <cmath>
#include <stdexcept>

#include "cosim/fluid_mps/boundaries.hpp"

namespace cosim::mps {
namespace {

int cells(double length, double l0) {
  return static_cast<int>(std::lround(length / l0));
}

// Bed columns ix in [first, last), rows -1 .. -(wall + dummy) below y = 0.
void add_bed(ParticleSet& set, double l0, int first, int last, int wall_layers, int dummy_layers) {
  for (int layer = 1; layer <= wall_layers + dummy_layers; ++layer) {
    const ParticleKind kind = layer <= wall_layers ? ParticleKind::wall : ParticleKind::dummy;
    for (int ix = first; ix < last; ++ix) {
      set.add(Eigen::Vector3d((ix + 0.5) * l0, (0.5 - layer) * l0, 0.0), kind);
    }
  }
}

// Bed slope sin(theta) as a gravity tilt: g = |g| (sin theta, -cos theta), flow along +x.
void tilt_gravity(MpsParameters& parameters, double slope) {
  if (std::abs(slope) >= 1.0) throw std::invalid_argument("channel scenes: |slope| < 1");
  if (slope == 0.0) return;
  const double g = parameters.gravity.norm();
  parameters.gravity = Eigen::Vector3d(g * slope, -g * std::sqrt(1.0 - slope * slope), 0.0);
}

void require_2d(const MpsParameters& p) {
  if (p.dimension != 2) throw std::invalid_argument("channel scenes are 2D (dimension = 2)");
}

}  // namespace

ParticleSet periodic_channel(MpsParameters& parameters, double length, double depth, double slope,
                             int wall_layers, int dummy_layers) {
  require_2d(parameters);
  tilt_gravity(parameters, slope);
  const double l0 = parameters.particle_spacing;
  const int nx = cells(length, l0), ny = cells(depth, l0);
  ParticleSet set;
  for (int iy = 0; iy < ny; ++iy)
    for (int ix = 0; ix < nx; ++ix)
      set.add(Eigen::Vector3d((ix + 0.5) * l0, (iy + 0.5) * l0, 0.0), ParticleKind::fluid);
  add_bed(set, l0, 0, nx, wall_layers, dummy_layers);
  parameters.periodic.enabled = true;
  parameters.periodic.x_min = 0.0;
  parameters.periodic.x_max = nx * l0;
  if (parameters.domain.isEmpty()) {
    const int layers = wall_layers + dummy_layers;
    parameters.domain =
        Eigen::AlignedBox3d(Eigen::Vector3d(-l0, -(layers + 2) * l0, -l0),
                            Eigen::Vector3d((nx + 1) * l0, 3.0 * depth + 10.0 * l0, l0));
  }
  return set;
}

ParticleSet open_channel(MpsParameters& parameters, OpenBoundarySettings& settings, double length,
                         double initial_depth, double block_height, int block_columns,
                         int pool_particles, int wall_layers, int dummy_layers, double slope) {
  require_2d(parameters);
  tilt_gravity(parameters, slope);
  const double l0 = parameters.particle_spacing;
  const int nx = cells(length, l0), ny = cells(initial_depth, l0);
  const int rows = cells(block_height, l0);
  const int layers = wall_layers + dummy_layers;
  if (rows < 1 || block_columns < 1) throw std::invalid_argument("open_channel: empty block");
  ParticleSet set;
  for (int iy = 0; iy < ny; ++iy)
    for (int ix = 0; ix < nx; ++ix)
      set.add(Eigen::Vector3d((ix + 0.5) * l0, (iy + 0.5) * l0, 0.0), ParticleKind::fluid);
  // Soluble moving wall block just upstream of the inflow line x = 0 (seed 001 section 2.2(3)).
  for (int c = 0; c < block_columns; ++c)
    for (int r = 0; r < rows; ++r)
      set.add(Eigen::Vector3d(-(c + 0.5) * l0, (r + 0.5) * l0, 0.0), ParticleKind::wall);
  add_bed(set, l0, -(block_columns + 2), nx, wall_layers, dummy_layers);
  // Pool of recycled particles, parked under the outlet.
  const Eigen::Vector3d park((nx + 4) * l0, -(layers + 6) * l0, 0.0);
  for (int k = 0; k < pool_particles; ++k) set.add(park, ParticleKind::inactive);
  settings.inflow_x = 0.0;
  settings.bed_y = 0.0;
  settings.block_rows = rows;
  settings.outflow_x = (nx + 3) * l0;
  settings.outflow_y_min = -(layers + 4) * l0;
  if (parameters.domain.isEmpty()) {
    parameters.domain = Eigen::AlignedBox3d(
        Eigen::Vector3d(-(block_columns + layers + 4) * l0, -(layers + 8) * l0, -l0),
        Eigen::Vector3d((nx + 6) * l0, 2.0 * block_height + 10.0 * l0, l0));
  }
  return set;
}

}  // namespace cosim::mps
