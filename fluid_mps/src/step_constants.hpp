// What the stages of FluidSystem::step (fluid_step.cpp, pressure_equation.cpp) share: the step's
// constants and the parallel fill of a work array.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "cosim/fluid_mps/fluid_system.hpp"

namespace cosim::mps {

struct FluidSystem::StepConstants {
  double dt;
  int n, d;
  double re_n, re_g, re_l, collision_distance, wall_collision_distance;
  double n0_n, n0_g, n0_l, lambda;
  Eigen::Vector3d driving;  // periodic channel: constant pressure drop as a body force
};

// v = n copies of value; no allocation once the capacity is there. In parallel from 4096
// items: under that the OpenMP fork/join costs more than the work.
template <class T>
void fill(std::vector<T>& v, std::size_t n, const T& value) {
  v.resize(n);
  const std::int64_t size = static_cast<std::int64_t>(n);
#pragma omp parallel for schedule(static) if (size >= 4096)
  for (std::int64_t i = 0; i < size; ++i) v[i] = value;
}

}  // namespace cosim::mps
