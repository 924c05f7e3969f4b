// The 3D fill lattices (MpsParameters::FillLattice, scenes_3d.cpp): the face-centred cubic fill
// has the cubic fill's volume l0^3 per particle, its interior particles start at its n0, and its
// wall particles have a full neighbourhood; its lattice sums against a direct count.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <utility>

#include "cosim/fluid_mps/fluid_system.hpp"
#include "cosim/fluid_mps/kernels.hpp"
#include "cosim/fluid_mps/scenes.hpp"
#include "quiet_settings.hpp"

using namespace cosim::mps;
using namespace cosim::mps::testing;

namespace {

MpsParameters fcc_parameters(double l0) {
  MpsParameters p;
  p.dimension = 3;
  p.particle_spacing = l0;
  p.gravity = Eigen::Vector3d(0.0, 0.0, -9.81);
  p.radius_gradient_over_l0 = 3.1;
  p.radius_laplacian_over_l0 = 3.1;
  p.fill_lattice = MpsParameters::FillLattice::fcc;
  return p;
}

}  // namespace

// The unstretched fcc lattice: 12 nearest neighbours at 2^(1/6) l0, 6 at 2^(2/3) l0 (the cube
// edge), 24 at sqrt(3) 2^(1/6) l0, the next at 2 2^(1/6) l0 (the fcc's shells at r^2 / d^2 =
// 1, 2, 3, 4 of its neighbour distance d; Ashcroft & Mermin ch. 4).
TEST(MpsFillLattice, FccShells) {
  const Eigen::Vector3d one = Eigen::Vector3d::Ones();
  const double first = std::pow(2.0, 1.0 / 6.0), second = std::pow(2.0, 2.0 / 3.0);
  const double third = std::sqrt(3.0) * first;
  EXPECT_EQ(fcc_lattice_sums(first + 1e-9, one).neighbour_count, 12);
  EXPECT_EQ(fcc_lattice_sums(second + 1e-9, one).neighbour_count, 18);
  EXPECT_EQ(fcc_lattice_sums(third + 1e-9, one).neighbour_count, 42);
  // n0 at radius re: the shells' weights re/r - 1.
  const double re = 2.1;
  const double expected = 12 * (re / first - 1) + 6 * (re / second - 1) + 24 * (re / third - 1);
  EXPECT_LT(third, re);
  EXPECT_GT(2.0 * first, re);  // the 4th shell, 2.24 l0, lies beyond 2.1 l0
  EXPECT_NEAR(fcc_lattice_sums(re, one).n0, expected, 1e-12);
  EXPECT_NEAR(fcc_layer_spacing_over_l0(), std::pow(2.0, -1.0 / 3.0), 1e-15);
}

// A tank 0.1 x 0.1 m with water 0.2 m deep: the fill fits a whole number of fcc layers (stretch
// under 1 %), holds the volume of the water in particles of the lattice's volume, every fluid
// particle deeper than the density radius and farther from the side walls starts at the n0 of
// that lattice, and every wall particle has the full neighbourhood of n0.
TEST(MpsFillLattice, FccTankVolumeDensityAndWalls) {
  const double l0 = 0.0125, length = 0.1, width = 0.1, depth = 0.2;
  MpsParameters p = fcc_parameters(l0);
  ParticleSet particles = still_water_tank_3d(p, length, width, depth, 0.25);
  for (int d = 0; d < 3; ++d) EXPECT_NEAR(p.fill_stretch[d], 1.0, 0.01);
  FluidSystem system(p, std::move(particles));
  const int fluid = count_kind(system, ParticleKind::fluid);
  EXPECT_EQ(fluid, 10 * 10 * 20 / 2);  // 10 x 10 x 20 layers of h = 0.01 m, half of them sites
  const double volume = fill_volume_per_particle(system.parameters());
  EXPECT_NEAR(volume / (l0 * l0 * l0), p.fill_stretch.prod(), 1e-12);
  EXPECT_NEAR(fluid * volume, length * width * depth, 1e-9 * length * width * depth);
  // The unstretched lattice's volume per particle is l0^3 exactly.
  MpsParameters unstretched = fcc_parameters(l0);
  EXPECT_NEAR(fill_volume_per_particle(unstretched), l0 * l0 * l0, 1e-18);
  const double reach = p.radius_density_over_l0 * l0, n0 = system.n0_density();
  int interior = 0, walls = 0;
  for (int i = 0; i < system.particle_count(); ++i) {
    const Eigen::Vector3d& x = system.positions()[i];
    const ParticleKind kind = system.kinds()[i];
    if (kind == ParticleKind::wall) {
      if (x.z() > depth - reach) continue;  // walls up the sides above the water lack the water
      ++walls;
      EXPECT_NEAR(system.number_densities()[i], n0, 1e-9 * n0) << "wall at " << x.transpose();
      continue;
    }
    if (kind != ParticleKind::fluid || x.z() > depth - reach) continue;
    ++interior;
    EXPECT_NEAR(system.number_densities()[i], n0, 1e-9 * n0) << "fluid at " << x.transpose();
  }
  EXPECT_GT(interior, fluid / 2);
  EXPECT_GT(walls, 0);
  EXPECT_GT(count_kind(system, ParticleKind::dummy), 0);
  // The nearest pair is the fcc neighbour distance 2^(1/6) h-stretched, above the collision
  // distance 1.0 l0 of still_water_3d.
  double nearest = 1e9;
  for (int i = 0; i < 200; ++i)
    for (int j = 0; j < system.particle_count(); ++j) {
      if (j != i)
        nearest = std::min(nearest, (system.positions()[j] - system.positions()[i]).norm());
    }
  EXPECT_NEAR(nearest / l0, std::sqrt(2.0) * fcc_layer_spacing_over_l0() * p.fill_stretch.x(),
              1e-9);
  EXPECT_GT(nearest, 1.1 * l0);
}

// The dam-break column keeps its size on the fcc fill: the layers are fitted to the column's far
// end along x and its top (the tank's far wall takes the nearest layer), so the column holds its
// volume a x a x 2a in particles of the lattice's volume, at a / l0 = 5 (6.3 layers of h across).
TEST(MpsFillLattice, FccDamBreakColumnKeepsItsVolume) {
  const double a = 0.05715, l0 = a / 5.0;
  MpsParameters p = fcc_parameters(l0);
  ParticleSet particles = dam_break_3d(p, a, 2.0 * a, 0.3, a, 0.15);
  FluidSystem system(p, std::move(particles));
  const int fluid = count_kind(system, ParticleKind::fluid);
  EXPECT_NEAR(fluid * fill_volume_per_particle(system.parameters()), 2.0 * a * a * a,
              1e-9 * a * a * a);
  double x_max = 0.0, z_max = 0.0;
  for (int i = 0; i < system.particle_count(); ++i) {
    if (system.kinds()[i] != ParticleKind::fluid) continue;
    x_max = std::max(x_max, system.positions()[i].x());
    z_max = std::max(z_max, system.positions()[i].z());
  }
  // The outermost layer lies half a layer inside the column's face.
  EXPECT_NEAR(x_max, a - 0.5 * fcc_layer_spacing_over_l0() * l0 * p.fill_stretch.x(), 1e-12);
  EXPECT_NEAR(z_max, 2.0 * a - 0.5 * fcc_layer_spacing_over_l0() * l0 * p.fill_stretch.z(), 1e-12);
}

// The fcc fill is 3D only, and the cubic fill is the default (its builders unchanged).
TEST(MpsFillLattice, FccNeeds3dAndCubicIsDefault) {
  MpsParameters p;
  EXPECT_EQ(p.fill_lattice, MpsParameters::FillLattice::cubic);
  p.fill_lattice = MpsParameters::FillLattice::fcc;
  EXPECT_THROW(validate_parameters(p), cosim::scenario::ParameterError);
  p.dimension = 3;
  EXPECT_NO_THROW(validate_parameters(p));
  MpsParameters cubic = fcc_parameters(0.01);
  cubic.fill_lattice = MpsParameters::FillLattice::cubic;
  const LatticeSums a = fill_lattice_sums(cubic, 2.1), b = lattice_sums(3, 2.1);
  EXPECT_EQ(a.n0, b.n0);
  EXPECT_EQ(a.lambda_over_l0sq, b.lambda_over_l0sq);
}
