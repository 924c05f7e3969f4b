// Throughput of the MPS step on the Martin & Moyce dam break at several resolutions:
// particle-steps per second and mean PCG iterations per step.
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdlib>

#include "cosim/fluid_mps/fluid_system.hpp"
#include "cosim/fluid_mps/scenes.hpp"

namespace {

// Settings for side-by-side runs of one binary: COSIM_BENCH_MULTIGRID_RADIUS (the amg
// hierarchy's radius / l0), COSIM_BENCH_SINGLE_PRODUCT (0 or 1: the CG products' float values)
// COSIM_BENCH_UPPER_TRIANGLE (0: full rows, 1: upper triangle; unset: automatic) and
// COSIM_BENCH_SETUP_REUSE (pressure_setup_reuse: solves one aggregation set-up may serve).
void apply_environment(cosim::mps::MpsParameters& p) {
  if (const char* radius = std::getenv("COSIM_BENCH_MULTIGRID_RADIUS")) {
    p.multigrid_radius_over_l0 = std::atof(radius);
  }
  if (const char* single = std::getenv("COSIM_BENCH_SINGLE_PRODUCT")) {
    p.single_precision_product = std::atoi(single) != 0;
  }
  if (const char* reuse = std::getenv("COSIM_BENCH_SETUP_REUSE")) {
    p.pressure_setup_reuse = std::atoi(reuse);
  }
  if (const char* upper = std::getenv("COSIM_BENCH_UPPER_TRIANGLE")) {
    p.pressure_product = std::atoi(upper) != 0
                             ? cosim::mps::MpsParameters::PressureProduct::upper_triangle
                             : cosim::mps::MpsParameters::PressureProduct::full_rows;
  }
}

// Milliseconds a step of each stage (StepReport::stage_seconds), as counters beside the step's
// time: where a size's time goes.
void count_stages(benchmark::State& state, const cosim::mps::StageSeconds& t, long steps) {
  const double per_step = 1e3 / static_cast<double>(steps);
  state.counters["ms_search"] = t.search * per_step;
  state.counters["ms_explicit"] = t.explicit_part * per_step;
  state.counters["ms_collision"] = t.collision * per_step;
  state.counters["ms_density"] = t.density * per_step;
  state.counters["ms_assembly"] = t.assembly * per_step;
  state.counters["ms_pressure_setup"] = t.pressure_setup * per_step;
  state.counters["ms_pressure_solve"] = t.pressure_solve * per_step;
  state.counters["ms_correction"] = t.correction * per_step;
  state.counters["ms_finish"] = t.finish * per_step;
}

void BM_DamBreakStep(benchmark::State& state) {
  using namespace cosim::mps;
  const double a = 0.05715;
  const int cells_per_width = static_cast<int>(state.range(0));
  MpsParameters p;
  p.particle_spacing = a / cells_per_width;
  p.max_dt = 0.25 * p.particle_spacing / std::sqrt(9.81 * 2.0 * a);
  p.pressure_preconditioner = static_cast<MpsParameters::PressurePreconditioner>(state.range(1));
  apply_environment(p);
  FluidSystem system(p, dam_break(p, a, 2.0 * a, 8.0 * a, 3.0 * a));
  // Skip the start-up so the column is collapsing (typical PCG work) when timing begins.
  while (system.time() < 0.05) system.step(system.stable_dt());
  long pcg_iterations = 0, steps = 0, searches = 0, unknowns = 0;
  StageSeconds stages;
  for (auto _ : state) {
    const StepReport report = system.step(system.stable_dt());
    stages += report.stage_seconds;
    pcg_iterations += report.pcg_iterations;
    searches += report.neighbour_searches;
    unknowns += report.pressure_unknowns;
    ++steps;
  }
  state.counters["particles"] = system.particle_count();
  state.counters["particle_steps_per_s"] = benchmark::Counter(
      static_cast<double>(system.particle_count()) * steps, benchmark::Counter::kIsRate);
  state.counters["mean_pcg_iterations"] = static_cast<double>(pcg_iterations) / steps;
  state.counters["searches_per_step"] = static_cast<double>(searches) / steps;
  state.counters["mean_unknowns"] = static_cast<double>(unknowns) / steps;
  count_stages(state, stages, steps);
}

// Arguments: a / l0, preconditioner (0 AMG, 1 Jacobi, 2 incomplete Cholesky, 3 automatic,
// 4 aggregation).
BENCHMARK(BM_DamBreakStep)
    ->ArgsProduct({{10, 20, 40, 80}, {0, 1, 4}})
    ->Unit(benchmark::kMillisecond)
    ->Iterations(200)
    ->UseRealTime();
// Sizes between a/l0 = 20 and 80 (the crossovers of the preconditioners, docs/performance.md).
BENCHMARK(BM_DamBreakStep)
    ->ArgsProduct({{24, 28, 32, 36, 48, 56, 64}, {0, 1}})
    ->Unit(benchmark::kMillisecond)
    ->Iterations(200)
    ->UseRealTime();

// 3D column collapse (a x 2a column over a tank 4a x a x 2a, radii 2.1 / 2.1 / 3.1 l0) at
// a/l0 = range(0): particle-steps per second, PPE iterations and bytes per particle.
void BM_Column3dStep(benchmark::State& state) {
  using namespace cosim::mps;
  const double a = 0.05715;
  MpsParameters p;
  p.dimension = 3;
  p.gravity = Eigen::Vector3d(0.0, 0.0, -9.81);
  p.radius_laplacian_over_l0 = 3.1;
  p.particle_spacing = a / static_cast<double>(state.range(0));
  p.max_dt = 0.25 * p.particle_spacing / std::sqrt(9.81 * 2.0 * a);
  p.pressure_preconditioner = static_cast<MpsParameters::PressurePreconditioner>(state.range(1));
  apply_environment(p);
  FluidSystem system(p, dam_break_3d(p, a, 2.0 * a, 4.0 * a, a, 2.0 * a));
  while (system.time() < 0.03) system.step(system.stable_dt());
  long pcg_iterations = 0, steps = 0, searches = 0, unknowns = 0;
  StageSeconds stages;
  for (auto _ : state) {
    const StepReport report = system.step(system.stable_dt());
    stages += report.stage_seconds;
    pcg_iterations += report.pcg_iterations;
    searches += report.neighbour_searches;
    unknowns += report.pressure_unknowns;
    ++steps;
  }
  state.counters["particles"] = system.particle_count();
  state.counters["particle_steps_per_s"] = benchmark::Counter(
      static_cast<double>(system.particle_count()) * steps, benchmark::Counter::kIsRate);
  state.counters["mean_pcg_iterations"] = static_cast<double>(pcg_iterations) / steps;
  state.counters["searches_per_step"] = static_cast<double>(searches) / steps;
  state.counters["mean_unknowns"] = static_cast<double>(unknowns) / steps;
  count_stages(state, stages, steps);
}

// Arguments: a / l0, preconditioner (0 AMG, 1 Jacobi, 4 aggregation).
BENCHMARK(BM_Column3dStep)
    ->ArgsProduct({{8, 12, 16}, {0, 1, 4}})
    ->Unit(benchmark::kMillisecond)
    ->Iterations(40)
    ->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
