// Throughput of the plant field: node sub-steps per second for fields of 20-link blades of
// seed 000 section 3(2) in a 0.15 m/s stream. Upright: rows 1 cm apart. Laid over: blades 3 mm
// apart along the stream, tilted 60 degrees downstream so that every blade leans on the next
// one along its whole length (all nodes in contact).
#include <benchmark/benchmark.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "beam_test_helpers.hpp"  // tests/vegetation_beam: the scenes' plants
#include "cosim/vegetation_beam/plant_field.hpp"

namespace {

using cosim::vegetation::BeamParameters;
using cosim::vegetation::PlantField;
using cosim::vegetation::PlantSpec;

PlantField make_field(int plants, bool laid_over, bool rigid) {
  PlantSpec blade;
  blade.length = 0.045;
  blade.links = 20;
  blade.width = 0.002;
  blade.thickness = 1.2e-4;
  blade.bending_stiffness = 8.67e-7;
  blade.youngs_modulus =
      12 * blade.bending_stiffness / (blade.width * std::pow(blade.thickness, 3));
  blade.density = 1000;
  const int per_row = static_cast<int>(std::ceil(std::sqrt(plants)));
  std::vector<PlantSpec> specs;
  for (int i = 0; i < plants; ++i) {
    PlantSpec spec = blade;
    const double spacing = laid_over ? 0.003 : 0.01;
    spec.base = Eigen::Vector3d(spacing * (i % per_row), 0, 0.01 * (i / per_row));
    specs.push_back(spec);
  }
  BeamParameters parameters;
  parameters.rigid = rigid;
  PlantField field(specs, parameters);
  if (laid_over) {
    const double angle = std::numbers::pi / 3;
    const Eigen::Vector3d lean(std::sin(angle), std::cos(angle), 0);
    std::vector<Eigen::Vector3d> positions = field.positions();
    for (int p = 0; p < field.plant_count(); ++p) {
      const auto [first, last] = field.node_range(p);
      for (int k = first; k < last; ++k)
        positions[k] = positions[first] + (k - first) * (blade.length / blade.links) * lean;
    }
    field.set_state(positions,
                    std::vector<Eigen::Vector3d>(positions.size(), Eigen::Vector3d::Zero()));
  }
  return field;
}

void advance_field(benchmark::State& state, bool laid_over, bool rigid) {
  PlantField field = make_field(static_cast<int>(state.range(0)), laid_over, rigid);
  const std::vector<Eigen::Vector3d> flow(field.node_count(), Eigen::Vector3d(0.15, 0, 0));
  const double window = 10 * field.stable_substep();  // ten sub-steps per call
  long long node_substeps = 0;
  int newton = 0;
  for (auto _ : state) {
    const auto report = field.advance(window, flow, flow);
    node_substeps += static_cast<long long>(report.substeps) * field.node_count();
    newton = std::max(newton, report.max_newton_iterations);
    benchmark::DoNotOptimize(field.positions().data());
  }
  state.counters["node_substeps_per_s"] =
      benchmark::Counter(static_cast<double>(node_substeps), benchmark::Counter::kIsRate);
  state.counters["nodes"] = field.node_count();
  state.counters["max_newton"] = newton;
}

void BM_Upright(benchmark::State& state) {
  advance_field(state, false, false);
}
void BM_LaidOverInContact(benchmark::State& state) {
  advance_field(state, true, false);
}
void BM_RigidUpright(benchmark::State& state) {
  advance_field(state, false, true);
}

// honami_field's reeds (seed 000 section 4): 200 plants of 10 links, 1 m tall, EI = 0.847 N m^2,
// specific gravity 0.5, C_D = 0.9, bent by a 1.5 m/s stream in 2 ms windows (the fluid's step),
// at `safety_factor`: 5 (five sub-steps a window; the scene's until December 2026) or 25 (one,
// the scene's now). reuse_jacobian: keep each plant's Jacobian over the window's sub-steps (the
// default), or factorise it at every sub-step.
void honami_reeds(benchmark::State& state, double safety_factor, bool reuse_jacobian) {
  std::vector<PlantSpec> specs;
  for (int i = 0; i < 200; ++i)
    specs.push_back(cosim::vegetation::testing::honami_reed(5.0 + 0.05 * i));
  BeamParameters parameters;
  parameters.gravity = Eigen::Vector3d(0, 0, -9.81);
  parameters.drag_coefficient = 0.9;
  parameters.safety_factor = safety_factor;
  parameters.reuse_jacobian = reuse_jacobian;
  PlantField field(specs, parameters);
  const std::vector<Eigen::Vector3d> flow(field.node_count(), Eigen::Vector3d(1.5, 0, 0));
  long long node_substeps = 0;
  int newton = 0;
  for (auto _ : state) {
    const auto report = field.advance(2e-3, flow, flow);
    node_substeps += static_cast<long long>(report.substeps) * field.node_count();
    newton = std::max(newton, report.max_newton_iterations);
    benchmark::DoNotOptimize(field.positions().data());
  }
  state.counters["node_substeps_per_s"] =
      benchmark::Counter(static_cast<double>(node_substeps), benchmark::Counter::kIsRate);
  state.counters["max_newton"] = newton;
}

// Arg: 1 keeps the Jacobian over the sub-steps (the default), 0 does not; safety_factor 5.
void BM_HonamiReeds(benchmark::State& state) {
  honami_reeds(state, 5, state.range(0) != 0);
}

// The scene's setting now: one sub-step a window, the defaults otherwise.
void BM_HonamiReedsOneSubstep(benchmark::State& state) {
  honami_reeds(state, 25, true);
}

BENCHMARK(BM_HonamiReeds)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_HonamiReedsOneSubstep)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Upright)->Arg(1)->Arg(100)->Arg(1000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_LaidOverInContact)->Arg(100)->Arg(1000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_RigidUpright)->Arg(1000)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
