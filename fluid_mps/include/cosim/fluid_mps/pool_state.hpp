// The developed state of one pool of a pool_fishway chain as the start of a periodic_pool scene
// (seed 001 section 3, Run-OC-4.18: the periodic pool started from t = 6.0 s of its three-pool
// run, the most downstream pool). The chain's pool k (counted from 1 at the inflow) spans
// x in [(k - 1) L, k L) with its floor at y = -(k - 1) step (pool_fishway), the periodic pool
// x in [0, L) with its floor at y = 0 (periodic_pool), both on the same cell lattice of l0: the
// shift (-(k - 1) L, (k - 1) step) maps one onto the other cell for cell. The chain's fluid
// particles inside the pool's reach are moved by it with their velocities and pressures; fluid
// outside it (the other pools, the outlet) is left out. Walls and dummies are the periodic
// builder's, so the scene keeps its own boundary; the chain's walls in the reach only serve to
// check that the two pools have the same geometry.
#pragma once

#include <Eigen/Core>
#include <stdexcept>
#include <string>
#include <utility>

#include "cosim/fluid_mps/fishway.hpp"
#include "cosim/fluid_mps/fluid_system.hpp"

namespace cosim::mps {

struct ChainPool {
  int pool = 0;                                     // counted from 1 at the inflow
  double x_min = 0.0, x_max = 0.0;                  // the pool's reach in the chain [m]
  Eigen::Vector2d shift = Eigen::Vector2d::Zero();  // chain position + shift: periodic pool
};

// The reach and shift of `pool` in a chain of the geometry's pools, on the lattice of l0.
ChainPool chain_pool(double particle_spacing, const FishwayGeometry& geometry, int pool);

// A chain frame that cannot start the periodic pool: which key of the scenario it concerns
// (file, pool) and why.
class ChainStateError : public std::invalid_argument {
 public:
  ChainStateError(std::string key, const std::string& reason)
      : std::invalid_argument(reason), key_(std::move(key)) {}
  const std::string& key() const { return key_; }

 private:
  std::string key_;
};

// The spacing of the frame's wall and dummy lattice in the pool's reach (the chain's moving
// inflow wall stands off the lattice, upstream of the first pool): the smallest gap between two
// distinct columns of boundary particles there (0 when there are fewer than two columns) [m].
double boundary_lattice_spacing(const MpsState& frame, const ChainPool& pool);

// Particles of `frame` (any kind but inactive) with x in the pool's reach, unshifted: what the
// bundle keeps of a chain run (fishway_pool_state).
MpsState extract_chain_pool(const MpsState& frame, const ChainPool& pool);

// The periodic pool's start: the frame's fluid in the pool's reach, shifted, then the walls and
// dummies of `periodic_scene` (periodic_pool's set) in their order, at rest, pressure zero (the
// first step's pressure solve sets them). Time and step start at zero. Throws ChainStateError
// when the frame holds no fluid in the reach (key pool), when its lattice spacing there differs
// from l0 (file), or when the chain's walls and dummies in the reach, shifted, are not the periodic
// scene's in x in [0, L) cell for cell (pool: another pool length, step, crest or partition).
MpsState periodic_pool_state(const ParticleSet& periodic_scene, const MpsState& frame,
                             const ChainPool& pool, double particle_spacing);

}  // namespace cosim::mps
