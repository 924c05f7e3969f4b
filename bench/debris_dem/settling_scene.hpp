// The settling case of bench/debris_dem, shared by the Google Benchmark (bench_settling.cpp) and
// the side-by-side run against LIGGGHTS (compare_case.cpp, compare_liggghts.py): spheres of
// d = 5-10 mm, seed 004 table 3 material, placed at random in the lower 0.13 m of a 0.2 x 0.2 x
// 0.3 m box of 10 triangles (open at the top), dt = 1e-5 s as in seed 004 table 3.
#pragma once

#include <memory>
#include <random>
#include <vector>

#include "cosim/debris_dem/dem_world.hpp"
#include "cosim/debris_dem/scenes.hpp"

namespace cosim::dem::bench {

constexpr double kBoxSide = 0.2;    // m, box floor is [0, 0.2]^2
constexpr double kBoxHeight = 0.3;  // m
constexpr double kPackTop = 0.13;   // m, spheres start below this height
constexpr double kTimeStep = 1e-5;  // s, seed 004 table 3

struct StartSphere {
  Eigen::Vector3d center;
  double diameter = 0.0;
};

inline std::unique_ptr<DemWorld> empty_box(int threads) {
  DemParameters p;
  p.user_dt = kTimeStep;
  p.threads = threads;
  auto world = std::make_unique<DemWorld>(p);
  const Material m;
  FlumeSpec box;
  box.length = kBoxSide;
  box.width = kBoxSide;
  box.wall_height = kBoxHeight;
  add_flume(*world, box, m);  // floor, y walls and the x = 0 wall: 8 triangles
  world->add_triangle({kBoxSide, 0, 0}, {kBoxSide, kBoxSide, 0}, {kBoxSide, kBoxSide, kBoxHeight},
                      m);
  world->add_triangle({kBoxSide, 0, 0}, {kBoxSide, kBoxSide, kBoxHeight}, {kBoxSide, 0, kBoxHeight},
                      m);
  return world;
}

// The random start of the benchmark (rejection placement, std::mt19937 seeds 1).
inline std::unique_ptr<DemWorld> settling_box(int spheres, int threads) {
  auto world = empty_box(threads);
  PackingSpec spec;
  spec.box_min = {0, 0, 0};
  spec.box_max = {kBoxSide, kBoxSide, kPackTop};
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> d(0.005, 0.01);
  for (int i = 0; i < spheres; ++i) spec.sphere_diameters.push_back(d(rng));
  const Material m;
  random_packing(*world, spec, m, m);
  return world;
}

// The same box with spheres at given start positions (element order: 10 triangles, then the
// spheres in the given order, as settling_box builds it).
inline std::unique_ptr<DemWorld> settling_box(const std::vector<StartSphere>& start, int threads) {
  auto world = empty_box(threads);
  const Material m;
  for (const StartSphere& s : start) world->add_sphere(s.center, 0.5 * s.diameter, m);
  return world;
}

}  // namespace cosim::dem::bench
