// Cost of the open and periodic boundaries: a periodic channel step (wrapped cell grid and
// minimum-image distances) and an open channel step plus OpenBoundaries::update (outflow scan,
// dissolution, pool), in particle-steps per second.
#include <benchmark/benchmark.h>

#include "cosim/fluid_mps/boundaries.hpp"
#include "cosim/fluid_mps/fluid_system.hpp"

namespace {

using namespace cosim::mps;

void BM_PeriodicChannelStep(benchmark::State& state) {
  MpsParameters p;
  p.particle_spacing = 0.1 / static_cast<double>(state.range(0));
  p.periodic.driving_pressure_drop = 20.0;
  FluidSystem system(p, periodic_channel(p, 0.4, 0.1, 0.00304));
  long steps = 0;
  for (auto _ : state) {
    system.step(system.stable_dt());
    ++steps;
  }
  state.counters["particles"] = system.particle_count();
  state.counters["particle_steps_per_s"] = benchmark::Counter(
      static_cast<double>(system.particle_count()) * steps, benchmark::Counter::kIsRate);
}

void BM_OpenChannelStep(benchmark::State& state) {
  MpsParameters p;
  p.particle_spacing = 0.05 / static_cast<double>(state.range(0));
  OpenBoundarySettings settings;
  FluidSystem system(p, open_channel(p, settings, 0.4, 0.03, 0.06, 4, 2000));
  settings.control = OpenBoundarySettings::Control::discharge;
  settings.discharge = 0.01;
  settings.inflow_rows = state.range(0) / 2;
  OpenBoundaries boundaries(system, settings);
  while (system.time() < 0.2) {
    system.step(system.stable_dt());
    boundaries.update();
  }
  long steps = 0;
  for (auto _ : state) {
    system.step(system.stable_dt());
    boundaries.update();
    ++steps;
  }
  int active = 0;  // the pool (inactive particles) costs nothing in the step
  for (auto kind : system.kinds()) active += kind != ParticleKind::inactive ? 1 : 0;
  state.counters["particles"] = active;
  state.counters["pool"] = boundaries.pool_size();
  state.counters["particle_steps_per_s"] =
      benchmark::Counter(static_cast<double>(active) * steps, benchmark::Counter::kIsRate);
}

// Argument: particles per 0.1 m depth (periodic) or per 0.05 m (open).
BENCHMARK(BM_PeriodicChannelStep)
    ->Arg(10)
    ->Arg(20)
    ->Unit(benchmark::kMillisecond)
    ->Iterations(100)
    ->UseRealTime();
BENCHMARK(BM_OpenChannelStep)
    ->Arg(10)
    ->Arg(20)
    ->Unit(benchmark::kMillisecond)
    ->Iterations(100)
    ->UseRealTime();

}  // namespace
