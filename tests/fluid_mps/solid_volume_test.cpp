// Solid volume in the fluid (FluidSystem::set_solid_volumes): water displaced by a submerged
// solid raises the level by V / A and the bed pressure by rho g V / A, and the water settles.
#include <gtest/gtest.h>

#include <iostream>

#include "cosim/fluid_mps/fluid_system.hpp"
#include "cosim/fluid_mps/scenes.hpp"
#include "quiet_settings.hpp"

using namespace cosim::mps;
using namespace cosim::mps::testing;

namespace {

struct Settled {
  double level = 0.0;         // mean free surface over the whole tank [m]
  double bed_pressure = 0.0;  // mean pressure near the bed [Pa]
  double max_speed = 0.0;     // over the averaging second [m/s]
  double largest_fraction = 0.0;
};

// 2D tank 0.1 m wide, water 0.1 m deep (l0 = 5 mm); `area` [m^2 per span] of solid at mid-depth,
// spread over 0.03 m (clear of the surface), grown over 0.5 s. Settle 1 s, average 1-2 s.
Settled settle(double area) {
  const double width = 0.1, depth = 0.1, l0 = 0.005;
  MpsParameters p = quiet_parameters(l0);
  FluidSystem system(p, still_water_tank(p, width, depth, 2.0 * depth));
  while (system.time() < 1.0) {
    if (area > 0.0) {  // grown over 0.5 s: an instant solid would blast the water away
      system.set_solid_volumes({Eigen::Vector3d(0.5 * width, 0.5 * depth, 0.0)},
                               {area * std::min(1.0, system.time() / 0.5)}, 0.03);
    }
    system.step(system.stable_dt());
  }
  Settled s;
  int samples = 0;
  std::vector<double> surface;
  while (system.time() < 2.0) {
    s.max_speed = std::max(s.max_speed, system.step(system.stable_dt()).max_speed);
    system.sample_surface({Eigen::Vector3d(0.5 * width, 0.0, 0.0)}, width, surface);
    s.level += surface[0];
    for (double x = 0.2 * width; x < 0.85 * width; x += 0.1 * width) {  // below the solid's reach
      s.bed_pressure += mean_pressure_at(system, Eigen::Vector3d(x, 1.5 * l0, 0.0), 1.5 * l0) / 7;
    }
    s.largest_fraction = std::max(s.largest_fraction, system.largest_solid_fraction());
    ++samples;
  }
  s.level /= samples;
  s.bed_pressure /= samples;
  return s;
}

}  // namespace

TEST(MpsSolidVolume, DisplacedWaterRaisesTheLevel) {
  const double area = 3e-4, width = 0.1;  // a 20 mm disk's area: the level rises 3 mm
  const Settled without = settle(0.0);
  const Settled with = settle(area);
  const double rise = with.level - without.level;
  const double pressure_rise = with.bed_pressure - without.bed_pressure;
  std::cout << "[solid volume] level " << without.level << " -> " << with.level << " m (rise "
            << rise << ", V/A " << area / width << "); bed pressure +" << pressure_rise
            << " Pa (rho g V/A " << 1000 * 9.81 * area / width << "); largest phi "
            << with.largest_fraction << ", max speed " << with.max_speed << " m/s\n";
  // Without displacement both would be zero. The level (highest particle per column) resolves a
  // fraction of l0 = 5 mm; the bed pressure carries the MPS pressure noise (about 2 % of the
  // 980 Pa, i.e. the size of the rise itself), so both are checked loosely.
  EXPECT_NEAR(rise, area / width, 0.3 * area / width);
  EXPECT_NEAR(pressure_rise, 1000 * 9.81 * area / width, 0.4 * 1000 * 9.81 * area / width);
  EXPECT_LT(with.largest_fraction, FluidSystem::kMaximumSolidFraction);
  EXPECT_LT(with.max_speed, 0.1);  // settled, not stirred
}

TEST(MpsSolidVolume, BadVolumesAreRefused) {
  MpsParameters p = quiet_parameters(0.01);
  FluidSystem system(p, still_water_tank(p, 0.1, 0.1, 0.2));
  EXPECT_THROW(system.set_solid_volumes({Eigen::Vector3d::Zero()}, {1.0, 2.0}, 0.1),
               std::invalid_argument);
  EXPECT_THROW(system.set_solid_volumes({Eigen::Vector3d::Zero()}, {-1.0}, 0.1),
               std::invalid_argument);
  EXPECT_THROW(system.set_solid_volumes({Eigen::Vector3d::Zero()}, {1.0}, 0.0),
               std::invalid_argument);
}
