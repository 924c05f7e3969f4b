// Soluble moving wall inflow with automatic level control and free outflow with particle
// recycling (seed 001 section 2.2(3)): prescribed discharge, particle conservation, level control.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <memory>

#include "cosim/fluid_mps/boundaries.hpp"
#include "cosim/fluid_mps/fluid_system.hpp"
#include "cosim/fluid_mps/observers.hpp"

#include "quiet_settings.hpp"

using namespace cosim::mps;
using namespace cosim::mps::testing;

// Fixed wall velocity: a column of inflow_rows fluid particles is released each time the block
// travels l0, and the particle count (fluid + block + pool + bed) never changes.
TEST(MpsOpenBoundaries, VelocityModeReleasesColumnsAndConservesParticles) {
  const double l0 = 0.01;
  MpsParameters p = quiet_parameters(l0);
  OpenBoundarySettings settings;
  FluidSystem system(p, open_channel(p, settings, 0.3, 0.0, 0.06, 4, 300));
  settings.control = OpenBoundarySettings::Control::velocity;
  settings.velocity = 0.2;
  settings.inflow_rows = 4;
  OpenBoundaries boundaries(system, settings);
  const int total = system.particle_count();
  const int bed = count_kind(system, ParticleKind::dummy) + count_kind(system, ParticleKind::wall) -
                  static_cast<int>(boundaries.block().size());
  const int block = static_cast<int>(boundaries.block().size());
  EXPECT_EQ(block, 4 * 6);
  while (system.time() < 0.5 - 1e-12) {
    system.step(1e-3);
    boundaries.update();
  }
  // The front column starts l0/2 before the line: columns passed = floor(U t / l0 + 1/2).
  const long columns = static_cast<long>(std::floor(0.2 * 0.5 / l0 + 0.5));
  EXPECT_EQ(boundaries.dissolved_total(), columns * 4);
  EXPECT_NEAR(boundaries.inflow_volume(), columns * 4 * l0 * l0, 1e-15);
  EXPECT_EQ(system.particle_count(), total);
  EXPECT_EQ(static_cast<int>(boundaries.block().size()), block);
  EXPECT_EQ(count_kind(system, ParticleKind::fluid),
            boundaries.dissolved_total() - boundaries.recycled_total());
  EXPECT_EQ(count_kind(system, ParticleKind::fluid) + block + boundaries.pool_size() + bed, total);
  for (int i : boundaries.block()) EXPECT_NEAR(system.velocities()[i].x(), 0.2, 1e-15);
}

// Seed 001's automatic level adjustment with a prescribed discharge per width q = 0.01 m^2/s on a
// 0.3 m channel ending in a free overfall: the gauge line half way counts q within a few % once
// the flow is established, and recycling keeps the particle count.
TEST(MpsOpenBoundaries, DischargeControlDeliversPrescribedDischarge) {
  const double l0 = 0.005, q = 0.01;
  MpsParameters p = quiet_parameters(l0);
  OpenBoundarySettings settings;
  FluidSystem system(p, open_channel(p, settings, 0.3, 0.025, 0.06, 4, 400));
  settings.control = OpenBoundarySettings::Control::discharge;
  settings.discharge = q;
  settings.inflow_rows = 6;
  OpenBoundaries boundaries(system, settings);
  const int total = system.particle_count();
  const int fluid0 = count_kind(system, ParticleKind::fluid);
  GaugeLine gauge(0.15);
  double line_sum = 0.0;
  int line_samples = 0;
  const DischargeCount count = count_discharge(system, boundaries, gauge, 1.5, 4.0, [&] {
    line_sum += discharge_through_line(system, 0.15, 0.0, 1.0, 2.0 * l0);
    ++line_samples;
  });
  const double q_in = count.inflow / count.seconds;
  const double q_gauge = count.gauge / count.seconds;
  const double q_line = line_sum / line_samples;
  std::cout << "[discharge control] q=" << q << " inflow " << q_in << " gauge " << q_gauge
            << " line " << q_line << " m^2/s; wall velocity " << boundaries.velocity()
            << " m/s rows " << boundaries.inflow_rows() << " level " << boundaries.measured_level()
            << " m; recycled " << boundaries.recycled_total() << " pool " << boundaries.pool_size()
            << "\n";
  EXPECT_NEAR(q_in, q, 0.02 * q);
  EXPECT_NEAR(q_gauge, q, 0.04 * q);
  EXPECT_NEAR(q_line, q, 0.08 * q);
  EXPECT_GT(boundaries.recycled_total(), 500);
  EXPECT_EQ(system.particle_count(), total);
  EXPECT_EQ(count_kind(system, ParticleKind::fluid),
            fluid0 + boundaries.dissolved_total() - boundaries.recycled_total());
}

// Level control: the wall velocity is adjusted (integral controller) until the level just
// downstream of the inflow reaches the target.
TEST(MpsOpenBoundaries, LevelControllerConvergesToTarget) {
  const double l0 = 0.005, target = 0.04;
  MpsParameters p = quiet_parameters(l0);
  OpenBoundarySettings settings;
  FluidSystem system(p, open_channel(p, settings, 0.3, 0.035, 0.06, 4, 400));
  settings.control = OpenBoundarySettings::Control::level;
  settings.target_level = target;
  settings.velocity = 0.2;
  settings.level_gain = 50.0;
  OpenBoundaries boundaries(system, settings);
  double level_sum = 0.0, velocity_sum = 0.0;
  int samples = 0;
  while (system.time() < 5.0) {
    system.step(system.stable_dt());
    if (boundaries.update().dissolved > 0 && system.time() > 3.5) {
      level_sum += boundaries.measured_level();
      velocity_sum += boundaries.velocity();
      ++samples;
    }
  }
  const double level = level_sum / samples;
  std::cout << "[level control] target " << target << " m, mean level (3.5-5 s) " << level
            << " m, mean wall velocity " << velocity_sum / samples << " m/s, q "
            << velocity_sum / samples * boundaries.inflow_rows() * l0 << " m^2/s\n";
  EXPECT_NEAR(level, target, 0.05 * target);
}

// A particle that leaves through the outflow (fluid -> inactive) or a block particle that
// dissolves (wall -> fluid, where it stands) keeps the pair list: inactive particles enter the
// stages far out of reach, so the next step needs no neighbour search. A particle taken from the
// pool (inactive -> wall, behind the block) moves from there by far more than the list's skin,
// so the step after searches. Against a twin restarted from its own state after every update
// (a fresh search at every step): the same bits.
TEST(MpsOpenBoundaries, LeavingParticlesKeepThePairListAndTheBits) {
  const double l0 = 0.01;
  MpsParameters p = quiet_parameters(l0);
  p.pressure_preconditioner = MpsParameters::PressurePreconditioner::aggregation;
  OpenBoundarySettings settings;
  settings.control = OpenBoundarySettings::Control::velocity;
  settings.velocity = 0.2;
  settings.inflow_rows = 4;
  const ParticleSet scene = open_channel(p, settings, 0.3, 0.03, 0.06, 4, 300);
  FluidSystem kept(p, scene);
  OpenBoundaries kept_boundaries(kept, settings);
  auto twin = std::make_unique<FluidSystem>(p, scene);
  auto twin_boundaries = std::make_unique<OpenBoundaries>(*twin, settings);
  int steps_after_leaving = 0, searched_after_leaving = 0;
  int steps_after_entering = 0, searched_after_entering = 0;
  BoundaryUpdate last;
  while (kept.time() < 0.4 - 1e-12) {
    const int searches = kept.step(1e-3).neighbour_searches;
    if (last.created > 0) {
      ++steps_after_entering;
      searched_after_entering += searches > 0 ? 1 : 0;
    } else if (last.recycled > 0 || last.dissolved > 0) {
      ++steps_after_leaving;
      searched_after_leaving += searches > 0 ? 1 : 0;
    }
    last = kept_boundaries.update();
    twin->step(1e-3);
    twin_boundaries->update();
    const OpenBoundaryState boundary_state = twin_boundaries->state();
    twin = std::make_unique<FluidSystem>(p, twin->save_state());
    twin_boundaries = std::make_unique<OpenBoundaries>(*twin, settings);
    twin_boundaries->restore(boundary_state);
  }
  EXPECT_GT(kept_boundaries.recycled_total(), 0);
  EXPECT_GT(kept_boundaries.dissolved_total(), 0);
  // Measured: 16 steps after particles left (and none entered), 5 of them with a search (the
  // skin's own), and each of the 8 steps after a column was created.
  EXPECT_GT(steps_after_leaving, 10);
  EXPECT_LT(searched_after_leaving, steps_after_leaving);
  EXPECT_GT(steps_after_entering, 0);
  EXPECT_EQ(searched_after_entering, steps_after_entering);
  ASSERT_EQ(kept.particle_count(), twin->particle_count());
  int differing = 0;
  for (int i = 0; i < kept.particle_count(); ++i) {
    if (kept.kinds()[i] != twin->kinds()[i] || kept.positions()[i] != twin->positions()[i] ||
        kept.velocities()[i] != twin->velocities()[i] ||
        kept.pressures()[i] != twin->pressures()[i]) {
      ++differing;
    }
  }
  EXPECT_EQ(differing, 0);
  std::cout << "[pair list kept] " << steps_after_leaving << " steps after particles left or "
            << "dissolved, " << searched_after_leaving << " with a search; " << steps_after_entering
            << " after a column was created, " << searched_after_entering << " with a search\n";
}
