#include "cosim/fluid_mps/scenes.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace cosim::mps {
namespace {

// Rectangular tank of inner size [0, length] x [0, height] with a bottom and two side walls.
// Column index ix covers centres x = (ix + 0.5) l0; negative indices are outside the tank.
void add_tank(ParticleSet& set, double l0, int cells_x, int cells_y, int wall_layers,
              int dummy_layers) {
  const int layers = wall_layers + dummy_layers;
  for (int iy = -layers; iy < cells_y; ++iy) {
    for (int ix = -layers; ix < cells_x + layers; ++ix) {
      const int depth_into_wall = std::max({-iy, -ix, ix - cells_x + 1, 0});
      if (depth_into_wall == 0) continue;  // inside the tank
      const ParticleKind kind =
          depth_into_wall <= wall_layers ? ParticleKind::wall : ParticleKind::dummy;
      set.add(Eigen::Vector3d((ix + 0.5) * l0, (iy + 0.5) * l0, 0.0), kind);
    }
  }
}

int cells(double length, double l0) {
  return static_cast<int>(std::lround(length / l0));
}

void set_domain(MpsParameters& p, double tank_length, double tank_height, int layers) {
  if (!p.domain.isEmpty()) return;
  const double l0 = p.particle_spacing;
  const double margin = (layers + 2) * l0;
  p.domain = Eigen::AlignedBox3d(Eigen::Vector3d(-margin, -margin, -l0),
                                 Eigen::Vector3d(tank_length + margin, 2.0 * tank_height, l0));
}

void require_2d(const MpsParameters& p) {
  if (p.dimension != 2)
    throw std::invalid_argument(
        "dam_break and still_water_tank are 2D (dimension = 2); in 3D use dam_break_3d, "
        "still_water_tank_3d or tank_3d");
}

// The library's vertical coordinate: y of the 2D plane (the world's z), z in 3D.
int vertical_axis(const FluidSystem& system) {
  return system.parameters().dimension == 3 ? 2 : 1;
}

}  // namespace

ParticleSet dam_break(MpsParameters& parameters, double column_width, double column_height,
                      double tank_length, double tank_height, int wall_layers, int dummy_layers) {
  require_2d(parameters);
  const double l0 = parameters.particle_spacing;
  ParticleSet set;
  const int nx = cells(column_width, l0), ny = cells(column_height, l0);
  for (int iy = 0; iy < ny; ++iy)
    for (int ix = 0; ix < nx; ++ix)
      set.add(Eigen::Vector3d((ix + 0.5) * l0, (iy + 0.5) * l0, 0.0), ParticleKind::fluid);
  add_tank(set, l0, cells(tank_length, l0), cells(tank_height, l0), wall_layers, dummy_layers);
  set_domain(parameters, tank_length, tank_height, wall_layers + dummy_layers);
  return set;
}

ParticleSet still_water_tank(MpsParameters& parameters, double width, double depth,
                             double tank_height, int wall_layers, int dummy_layers) {
  return dam_break(parameters, width, depth, width, tank_height, wall_layers, dummy_layers);
}

double surge_front_position(const FluidSystem& system, double bed_height, double band) {
  const double l0 = system.parameters().particle_spacing;
  if (band < 0.0) band = 2.0 * l0;
  const int up = vertical_axis(system);
  double front = -std::numeric_limits<double>::infinity();
  for (int i = 0; i < system.particle_count(); ++i) {
    if (system.kinds()[i] != ParticleKind::fluid) continue;
    const Eigen::Vector3d& x = system.positions()[i];
    if (x[up] - bed_height <= band) front = std::max(front, x.x());
  }
  return front + 0.5 * l0;
}

double residual_column_height(const FluidSystem& system, double wall_x, double band) {
  const double l0 = system.parameters().particle_spacing;
  if (band < 0.0) band = 2.0 * l0;
  const int up = vertical_axis(system);
  double height = -std::numeric_limits<double>::infinity();
  for (int i = 0; i < system.particle_count(); ++i) {
    if (system.kinds()[i] != ParticleKind::fluid) continue;
    const Eigen::Vector3d& x = system.positions()[i];
    if (x.x() - wall_x <= band) height = std::max(height, x[up]);
  }
  return height + 0.5 * l0;
}

namespace {

// The mean of value(i, x_i - point) over the fluid particles within `radius` of `point`
// (0 if none).
template <class Value>
double mean_over_fluid_near(const FluidSystem& system, const Eigen::Vector3d& point, double radius,
                            Value value) {
  double sum = 0.0;
  int count = 0;
  for (int i = 0; i < system.particle_count(); ++i) {
    if (system.kinds()[i] != ParticleKind::fluid) continue;
    const Eigen::Vector3d offset = system.positions()[i] - point;
    if (offset.norm() < radius) {
      sum += value(i, offset);
      ++count;
    }
  }
  return count > 0 ? sum / count : 0.0;
}

}  // namespace

double mean_pressure_at(const FluidSystem& system, const Eigen::Vector3d& point, double radius) {
  return mean_over_fluid_near(system, point, radius,
                              [&](int i, const Eigen::Vector3d&) { return system.pressures()[i]; });
}

double hydrostatic_pressure_at(const FluidSystem& system, const Eigen::Vector3d& point,
                               double radius) {
  const MpsParameters& p = system.parameters();
  return mean_over_fluid_near(system, point, radius, [&](int i, const Eigen::Vector3d& offset) {
    return carried_hydrostatically(system.pressures()[i], -offset, p.density, p.gravity);
  });
}

}  // namespace cosim::mps
