// Scene builders (2D unless named _3d) and observers of FluidSystem used by validation tests and
// benchmarks.
#pragma once

#include <Eigen/Core>

#include "cosim/fluid_mps/fluid_system.hpp"
#include "cosim/fluid_mps/parameters.hpp"

namespace cosim::mps {

// Open-topped tank: bed y in [-layers l0, 0), side walls outside x in [0, tank_length].
// Particles sit at cell centres, so fluid fills x in [0, width], y in [0, height] exactly.
// The first `wall_layers` layers are wall particles (pressure solved), the next `dummy_layers`
// are dummy particles (they only complete the number density).
// Also sets parameters.domain if it is empty (tank grown by a margin; taller for splashes).
ParticleSet dam_break(MpsParameters& parameters, double column_width, double column_height,
                      double tank_length, double tank_height, int wall_layers = 2,
                      int dummy_layers = 2);

// 3D column collapse in the world frame (x along the tank, y across, z up; set gravity along
// -z): a closed-sided tank [0, tank_length] x [0, tank_width] x [0, tank_height] with a floor and
// four side walls, water in x < column_length, z < column_height over the whole width.
ParticleSet dam_break_3d(MpsParameters& parameters, double column_length, double column_height,
                         double tank_length, double tank_width, double tank_height,
                         int wall_layers = 2, int dummy_layers = 2);

ParticleSet still_water_tank(MpsParameters& parameters, double width, double depth,
                             double tank_height, int wall_layers = 2, int dummy_layers = 2);

// Surge front: largest x of fluid particles within `band` (default 2 l0) of the bed at
// y = bed_height, plus l0/2 (particle edge).
double surge_front_position(const FluidSystem& system, double bed_height = 0.0, double band = -1.0);

// Residual column: largest y of fluid particles within `band` (default 2 l0) of the left wall
// at x = wall_x, plus l0/2 (particle edge).
double residual_column_height(const FluidSystem& system, double wall_x = 0.0, double band = -1.0);

// Mean pressure of the fluid particles within `radius` of `point` (0 if none).
double mean_pressure_at(const FluidSystem& system, const Eigen::Vector3d& point, double radius);

}  // namespace cosim::mps
