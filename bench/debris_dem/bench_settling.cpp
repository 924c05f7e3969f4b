// 5000 spheres (d = 5-10 mm, seed 004 material) dropped into a box (settling_scene.hpp) and
// settling, dt = 1e-5 s as in seed 004 table 3. Reports sphere-steps per second (items_per_second);
// second argument: DemParameters::threads.
#include <benchmark/benchmark.h>

#include "settling_scene.hpp"

namespace {

using cosim::dem::bench::settling_box;

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
