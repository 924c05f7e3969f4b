// Scene builders (2D, and 3D ones named _3d: src/scenes_3d.cpp) and observers of FluidSystem used
// by validation tests, benchmarks and the fluid_mps process.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <filesystem>
#include <vector>

#include "cosim/fluid_mps/fluid_system.hpp"
#include "cosim/fluid_mps/parameters.hpp"
#include "cosim/scenario/stl.hpp"

namespace cosim::mps {

// Open-topped tank: bed y in [-layers l0, 0), side walls outside x in [0, tank_length].
// Particles sit at cell centres, so fluid fills x in [0, width], y in [0, height] exactly.
// The first `wall_layers` layers are wall particles (pressure solved), the next `dummy_layers`
// are dummy particles (they only complete the number density).
// Also sets parameters.domain if it is empty (tank grown by a margin; taller for splashes).
ParticleSet dam_break(MpsParameters& parameters, double column_width, double column_height,
                      double tank_length, double tank_height, int wall_layers = 2,
                      int dummy_layers = 2);

ParticleSet still_water_tank(MpsParameters& parameters, double width, double depth,
                             double tank_height, int wall_layers = 2, int dummy_layers = 2);

// 3D scenes, in the world frame: x along the tank, y across, z up (set gravity along -z). The
// lattice has cells of size l0 with particles at their centres; the tank's inner space is
// [0, length] x [0, width] x [0, height] (each rounded to whole cells), closed by a floor and
// four side walls and open at the top. A cell is solid when it lies outside the inner space or
// its centre lies inside an obstacle box or a closed triangle surface (`solids` of tank_3d). Solid
// cells within `wall_layers` cells (Chebyshev distance, so edges and corners are filled) of an open
// cell hold wall particles (pressure solved), the next `dummy_layers` hold dummy particles (number
// density only), deeper ones hold nothing. Open cells whose centre lies in one of the water boxes
// hold fluid particles, at rest. Each builder sets parameters.domain if it is empty (the tank grown
// by the wall layers and two cells; twice the tank height for splashes) and needs
// parameters.dimension == 3.
struct Tank3d {
  double length = 0.0, width = 0.0, height = 0.0;  // inner size along x, y, z [m]
  std::vector<Eigen::AlignedBox3d> obstacles;      // solid boxes [m], e.g. on the floor
  int wall_layers = 2, dummy_layers = 2;
};
// A closed triangle surface [m] (a solid's outline, e.g. read from an STL file): a cell whose
// centre lies inside it (odd number of crossings along a ray) is solid, like an obstacle box.
// The type and the STL reader are the scenario library's (cosim/scenario/stl.hpp), which the DEM
// reads its wall triangles with too.
using scenario::read_stl;
using scenario::Triangle;
using scenario::TriangleMesh;
bool inside_mesh(const TriangleMesh& mesh, const Eigen::Vector3d& point);

ParticleSet tank_3d(MpsParameters& parameters, const Tank3d& tank,
                    const std::vector<Eigen::AlignedBox3d>& water,
                    const std::vector<TriangleMesh>& solids = {});

// Column collapse: water in x < column_length, z < column_height over the whole width of a tank
// [0, tank_length] x [0, tank_width] x [0, tank_height].
ParticleSet dam_break_3d(MpsParameters& parameters, double column_length, double column_height,
                         double tank_length, double tank_width, double tank_height,
                         int wall_layers = 2, int dummy_layers = 2);

// Water at rest, `depth` deep, filling a tank `length` (x) by `width` (y).
ParticleSet still_water_tank_3d(MpsParameters& parameters, double length, double width,
                                double depth, double tank_height, int wall_layers = 2,
                                int dummy_layers = 2);

// SPHERIC benchmark 2 (Kleefsman et al. 2005; references/spheric_test2.md): tank 3.22 x 1.0 x
// 1.0 m, water x in [1.992, 3.22] m over the full width, 0.55 m deep, and a box on the floor,
// x in [0.6635, 0.8245], y in [0.2955, 0.6985], z in [0, 0.161] m.
Tank3d spheric_test2_tank(int wall_layers = 2, int dummy_layers = 2);
ParticleSet spheric_test2(MpsParameters& parameters, int wall_layers = 2, int dummy_layers = 2);

// Measures of a column collapse. The vertical axis is the library's last coordinate: y in 2D
// (the world's z, docs/architecture.md), z in 3D. In 3D both take the extreme over the whole
// width of the tank (the leading particle anywhere across y, not a mean over y), the same
// definition as in 2D.
//
// Surge front: largest x of fluid particles within `band` (default 2 l0) of the bed at
// height bed_height, plus l0/2 (particle edge).
double surge_front_position(const FluidSystem& system, double bed_height = 0.0, double band = -1.0);

// Residual column: largest height of fluid particles within `band` (default 2 l0) of the back
// wall at x = wall_x, plus l0/2 (particle edge).
double residual_column_height(const FluidSystem& system, double wall_x = 0.0, double band = -1.0);

// Mean pressure of the fluid particles within `radius` of `point` (0 if none).
double mean_pressure_at(const FluidSystem& system, const Eigen::Vector3d& point, double radius);

// The pressure at `point` that the fluid particles within `radius` give when each one's pressure
// is carried hydrostatically to the point, p_j + rho g . (point - x_j), and averaged (0 if none):
// the particles' pressures measured against the hydrostatic field at their own positions. Unlike
// the plain mean it does not read rho g times the offset of the sample's centroid from the point,
// which on a lattice that stays put (the same 10-20 particles every step, their centroid a
// fraction of l0 off the point) does not average out in time. Exact for any hydrostatic field.
double hydrostatic_pressure_at(const FluidSystem& system, const Eigen::Vector3d& point,
                               double radius);

}  // namespace cosim::mps
