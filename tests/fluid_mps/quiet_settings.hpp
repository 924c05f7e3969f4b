// Settings and counts shared by the fluid_mps tests.
#pragma once

#include <algorithm>
#include <functional>
#include <vector>

#include "cosim/fluid_mps/boundaries.hpp"
#include "cosim/fluid_mps/fluid_system.hpp"
#include "cosim/fluid_mps/observers.hpp"
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

// The level of the water as a uniform layer on a floor at z = 0: twice the mean height of its
// fluid particles [m] (the hydrostatic reference's water level, fluid_mps/process/references.cpp).
inline double layer_level(const FluidSystem& system) {
  double height = 0.0;
  int fluid = 0;
  for (int i = 0; i < system.particle_count(); ++i) {
    if (system.kinds()[i] != ParticleKind::fluid) continue;
    height += system.positions()[i].z();
    ++fluid;
  }
  return 2.0 * height / fluid;
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

// What an open channel delivered over [t_start, t_end]: the volume its inflow released and the
// net volume through a gauge line [m^3, m^2 in 2D], and the time it took [s].
struct DischargeCount {
  double inflow = 0.0, gauge = 0.0, seconds = 0.0;
};

// Steps `system` at its stable step to t_end, updating its open boundaries and the gauge after
// every step; counts from the first step end at or past t_start, where `sample` (if any) also
// runs after every step.
inline DischargeCount count_discharge(FluidSystem& system, OpenBoundaries& boundaries,
                                      GaugeLine& gauge, double t_start, double t_end,
                                      const std::function<void()>& sample = {}) {
  double inflow0 = 0.0, start = 0.0;
  long gauge0 = 0;
  bool started = false;
  while (system.time() < t_end) {
    system.step(system.stable_dt());
    boundaries.update();
    gauge.update(system);
    if (!started && system.time() >= t_start) {
      started = true;
      start = system.time();
      inflow0 = boundaries.inflow_volume();
      gauge0 = gauge.net_particles();
    }
    if (started && sample) sample();
  }
  const double particle = fill_volume_per_particle(system.parameters());
  return {boundaries.inflow_volume() - inflow0,
          static_cast<double>(gauge.net_particles() - gauge0) * particle, system.time() - start};
}

}  // namespace cosim::mps::testing
