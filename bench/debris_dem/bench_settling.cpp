// 5000 spheres (d = 5-10 mm, seed 004 material) dropped into a closed box and settling, dt = 1e-5
// s as in seed 004 table 3. Reports sphere-steps per second (items_per_second); second
// argument: DemParameters::threads.
#include <benchmark/benchmark.h>

#include <memory>
#include <random>

#include "cosim/debris_dem/dem_world.hpp"
#include "cosim/debris_dem/scenes.hpp"

namespace {

using cosim::dem::DemParameters;
using cosim::dem::DemWorld;
using cosim::dem::Material;

std::unique_ptr<DemWorld> settling_box(int spheres, int threads) {
  DemParameters p;
  p.user_dt = 1e-5;
  p.threads = threads;
  auto world = std::make_unique<DemWorld>(p);
  Material m;
  const double side = 0.2;
  const double height = 0.3;
  cosim::dem::FlumeSpec box;
  box.length = side;
  box.width = side;
  box.wall_height = height;
  cosim::dem::add_flume(*world, box, m);
  world->add_triangle({side, 0, 0}, {side, side, 0}, {side, side, height}, m);
  world->add_triangle({side, 0, 0}, {side, side, height}, {side, 0, height}, m);
  cosim::dem::PackingSpec spec;
  spec.box_min = {0, 0, 0};
  spec.box_max = {side, side, 0.13};
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> d(0.005, 0.01);
  for (int i = 0; i < spheres; ++i) spec.sphere_diameters.push_back(d(rng));
  cosim::dem::random_packing(*world, spec, m, m);
  return world;
}

void BM_SettlingSpheres(benchmark::State& state) {
  const int spheres = static_cast<int>(state.range(0));
  auto world = settling_box(spheres, static_cast<int>(state.range(1)));
  world->advance(0.15, {}, {});  // after the fall: a dense pile, thousands of contacts
  long long steps = 0;
  for (auto _ : state) {
    const auto report = world->advance(1e-3, {}, {});
    steps += report.substeps;
    benchmark::DoNotOptimize(report.contacts);
  }
  state.SetItemsProcessed(steps * spheres);
  state.counters["contacts"] = world->contact_count();
  state.counters["sim_time_s"] = world->time();
}
BENCHMARK(BM_SettlingSpheres)
    ->Args({5000, 1})
    ->Args({5000, 2})
    ->Iterations(40)
    ->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
