// Settings and counts shared by the fluid_mps tests.
#pragma once

#include <algorithm>
#include <vector>

#include "cosim/fluid_mps/fluid_system.hpp"
#include "cosim/fluid_mps/parameters.hpp"

namespace cosim::mps::testing {

// Seed 001's collision distance 1.0 l0 (C_c = 0.2) and a 4.0 l0 gradient radius: the quiet
// settings of the still-water, channel, partition and fishway tests.
inline MpsParameters quiet_parameters(double l0) {
  MpsParameters p;
  p.particle_spacing = l0;
  p.max_dt = 1e-3;
  p.collision_distance_ratio = 1.0;
  p.collision_restitution = 0.2;
  p.radius_gradient_over_l0 = 4.0;
  return p;
}

inline int count_kind(const std::vector<ParticleKind>& kinds, ParticleKind kind) {
  return static_cast<int>(std::count(kinds.begin(), kinds.end(), kind));
}
inline int count_kind(const FluidSystem& system, ParticleKind kind) {
  return count_kind(system.kinds(), kind);
}
inline int count_kind(const ParticleSet& set, ParticleKind kind) {
  return count_kind(set.kinds, kind);
}

}  // namespace cosim::mps::testing
