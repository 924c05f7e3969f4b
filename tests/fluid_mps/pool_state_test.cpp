// A periodic_pool started from one pool of a pool_fishway chain (pool_state.hpp): the chain's
// fluid in the pool's reach lands shifted on the periodic pool's lattice with its velocity and
// pressure, the periodic scene's walls stay as built, and frames that cannot start the pool
// (another resolution, no fluid in the pool, another geometry) are refused with the key.
#include <gtest/gtest.h>

#include <cmath>

#include "cosim/fluid_mps/pool_state.hpp"

#include "quiet_settings.hpp"

using namespace cosim::mps;
using namespace cosim::mps::testing;

namespace {

// Distinct, position-dependent velocities and pressures, so a particle's own values are checked.
Eigen::Vector3d velocity_at(const Eigen::Vector3d& x) {
  return {0.3 + 2.0 * x.x(), -0.1 + 5.0 * x.y(), 0.0};
}
double pressure_at(const Eigen::Vector3d& x) {
  return 1000.0 + 3000.0 * x.x() - 9810.0 * x.y();
}

// A chain frame: the pool_fishway set with those velocities and pressures on its fluid.
MpsState chain_frame(double l0, const FishwayGeometry& geometry) {
  MpsParameters p = quiet_parameters(l0);
  OpenBoundarySettings inflow;
  std::vector<Weir> weirs;
  const ParticleSet set = pool_fishway(p, inflow, geometry, weirs);
  MpsState state;
  state.time = 6.0;
  for (std::size_t i = 0; i < set.size(); ++i) {
    const bool fluid = set.kinds[i] == ParticleKind::fluid;
    state.positions.push_back(set.positions[i]);
    state.velocities.push_back(fluid ? velocity_at(set.positions[i]) : Eigen::Vector3d::Zero());
    state.pressures.push_back(fluid ? pressure_at(set.positions[i]) : 0.0);
    state.kinds.push_back(set.kinds[i]);
  }
  return state;
}

ParticleSet periodic_scene(double l0, const FishwayGeometry& geometry) {
  MpsParameters p = quiet_parameters(l0);
  std::vector<Weir> weirs;
  return periodic_pool(p, geometry, geometry.weir_height + 0.02, weirs);
}

std::string key_of_refusal(const ParticleSet& scene, const MpsState& frame, const ChainPool& pool,
                           double l0) {
  try {
    periodic_pool_state(scene, frame, pool, l0);
  } catch (const ChainStateError& error) {
    return error.key();
  }
  return "";
}

}  // namespace

TEST(PoolState, ChainPoolReachAndShiftOnTheLattice) {
  const FishwayGeometry g;  // 0.3 m pools, 0.05 m steps
  const ChainPool pool = chain_pool(0.00666, g, 3);
  // 45 cells of 6.66 mm per pool (0.2997 m), the step rounds to 8 cells (0.05328 m).
  EXPECT_NEAR(pool.x_min, 2 * 45 * 0.00666, 1e-12);
  EXPECT_NEAR(pool.x_max, 3 * 45 * 0.00666, 1e-12);
  EXPECT_NEAR(pool.shift.x(), -pool.x_min, 1e-12);
  EXPECT_NEAR(pool.shift.y(), 2 * 8 * 0.00666, 1e-12);
}

TEST(PoolState, EveryPoolOfTheChainLandsOnThePeriodicPool) {
  const double l0 = 0.01;
  const FishwayGeometry g;
  const MpsState frame = chain_frame(l0, g);
  const ParticleSet scene = periodic_scene(l0, g);
  EXPECT_NEAR(boundary_lattice_spacing(frame, chain_pool(l0, g, 2)), l0, 1e-12);
  const int scene_boundary =
      count_kind(scene, ParticleKind::wall) + count_kind(scene, ParticleKind::dummy);
  for (int k = 1; k <= g.pools; ++k) {
    const ChainPool pool = chain_pool(l0, g, k);
    const MpsState state = periodic_pool_state(scene, frame, pool, l0);
    // pool_fishway fills every pool up to its crest: 30 columns minus the partition's 2, 20 rows.
    const int fluid = count_kind(state.kinds, ParticleKind::fluid);
    EXPECT_EQ(fluid, 28 * 20) << "pool " << k;
    EXPECT_EQ(static_cast<int>(state.positions.size()), fluid + scene_boundary);
    EXPECT_EQ(state.time, 0.0);
    for (int i = 0; i < fluid; ++i) {
      const Eigen::Vector3d& x = state.positions[i];
      // The same floor: the pool's water sits from y = 0 up to the crest, inside [0, L).
      EXPECT_GE(x.x(), 0.0);
      EXPECT_LT(x.x(), 0.3);
      EXPECT_GT(x.y(), 0.0);
      EXPECT_LT(x.y(), g.weir_height);
      // Its chain position, velocity and pressure: the shift back, the values unchanged.
      const Eigen::Vector3d chain = x - Eigen::Vector3d(pool.shift.x(), pool.shift.y(), 0.0);
      EXPECT_GE(chain.x(), pool.x_min);
      EXPECT_LT(chain.x(), pool.x_max);
      // (the shift back rounds in the last bit: the velocity field's slope is a few 1/s)
      EXPECT_LT((state.velocities[i] - velocity_at(chain)).norm(), 1e-12);
      EXPECT_NEAR(state.pressures[i], pressure_at(chain), 1e-9);
    }
    // The periodic scene's walls and dummies, in their order, where the builder put them.
    int b = fluid;
    for (std::size_t i = 0; i < scene.size(); ++i) {
      if (scene.kinds[i] == ParticleKind::fluid) continue;
      ASSERT_LT(b, static_cast<int>(state.positions.size()));
      EXPECT_EQ(state.positions[b], scene.positions[i]);
      EXPECT_EQ(state.kinds[b], scene.kinds[i]);
      EXPECT_EQ(state.velocities[b], Eigen::Vector3d::Zero());
      ++b;
    }
  }
}

TEST(PoolState, TheKeptPoolStartsTheSameState) {
  const double l0 = 0.01;
  const FishwayGeometry g;
  const MpsState frame = chain_frame(l0, g);
  const ChainPool pool = chain_pool(l0, g, 2);
  const MpsState kept = extract_chain_pool(frame, pool);
  EXPECT_LT(kept.positions.size(), frame.positions.size());
  for (const auto& x : kept.positions) {
    EXPECT_GE(x.x(), pool.x_min);
    EXPECT_LT(x.x(), pool.x_max);
  }
  const ParticleSet scene = periodic_scene(l0, g);
  const MpsState from_frame = periodic_pool_state(scene, frame, pool, l0);
  const MpsState from_kept = periodic_pool_state(scene, kept, pool, l0);
  EXPECT_EQ(from_kept.positions, from_frame.positions);
  EXPECT_EQ(from_kept.velocities, from_frame.velocities);
  EXPECT_EQ(from_kept.pressures, from_frame.pressures);
}

TEST(PoolState, FramesThatCannotStartThePoolAreRefusedWithTheirKey) {
  const double l0 = 0.01;
  const FishwayGeometry g;
  const MpsState frame = chain_frame(l0, g);
  // A pool the chain does not have: no fluid past the third.
  EXPECT_EQ(key_of_refusal(periodic_scene(l0, g), frame, chain_pool(l0, g, 4), l0), "pool");
  // A chain at another resolution.
  const double fine = 0.00666;
  EXPECT_EQ(key_of_refusal(periodic_scene(fine, g), frame, chain_pool(fine, g, 2), fine), "file");
  // Another crest height, step or pool length in the periodic scene.
  FishwayGeometry lower = g;
  lower.weir_height = 0.15;
  EXPECT_EQ(key_of_refusal(periodic_scene(l0, lower), frame, chain_pool(l0, lower, 2), l0), "pool");
  FishwayGeometry steeper = g;
  steeper.step_height = 0.08;
  EXPECT_EQ(key_of_refusal(periodic_scene(l0, steeper), frame, chain_pool(l0, steeper, 2), l0),
            "pool");
  FishwayGeometry longer = g;
  longer.pool_length = 0.4;
  EXPECT_EQ(key_of_refusal(periodic_scene(l0, longer), frame, chain_pool(l0, longer, 2), l0),
            "pool");
}
