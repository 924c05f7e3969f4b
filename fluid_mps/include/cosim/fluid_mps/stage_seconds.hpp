// Wall-time bookkeeping of the fluid step: the stages' seconds (StepReport::stage_seconds) and
// the steady clock they are read from.
#pragma once

#include <chrono>

namespace cosim::mps {

using StageClock = std::chrono::steady_clock;

// [s] on the steady clock from `from` to `to`, and from `start` to now.
inline double seconds_between(StageClock::time_point from, StageClock::time_point to) {
  return std::chrono::duration<double>(to - from).count();
}
inline double seconds_since(StageClock::time_point start) {
  return seconds_between(start, StageClock::now());
}

// Wall seconds of the stages of a step (FluidSystem::step), for a run's profile: where the time
// goes, not a result (they differ between runs). The neighbour search is counted apart from the
// stages it runs in.
struct StageSeconds {
  double search = 0.0;         // pair lists and the particles' reordering
  double explicit_part = 0.0;  // viscosity, gravity, point forces
  double collision = 0.0;
  double density = 0.0;         // number densities, surface, divergence
  double assembly = 0.0;        // the pressure equation
  double pressure_setup = 0.0;  // the preconditioner's set-up
  double pressure_solve = 0.0;  // conjugate gradients
  double correction = 0.0;      // pressure gradient, shifting
  double finish = 0.0;          // state out, stability check
  StageSeconds& operator+=(const StageSeconds& o) {
    search += o.search;
    explicit_part += o.explicit_part;
    collision += o.collision;
    density += o.density;
    assembly += o.assembly;
    pressure_setup += o.pressure_setup;
    pressure_solve += o.pressure_solve;
    correction += o.correction;
    finish += o.finish;
    return *this;
  }
};

}  // namespace cosim::mps
