#include "cosim/fluid_mps/checkpoint.hpp"

#include <cstdint>
#include <vector>

namespace cosim::mps {

void save_checkpoint(const FluidSystem& system, checkpoint::Writer& out) {
  save_checkpoint(system.save_state(), system.parameters().dimension, out);
}

void save_checkpoint(const MpsState& state, int dimension, checkpoint::Writer& out) {
  out.value("fluid.schema", kFluidCheckpointSchema);
  out.value("fluid.dimension", dimension);
  out.vector("fluid.positions", state.positions);
  out.vector("fluid.velocities", state.velocities);
  out.vector("fluid.pressures", state.pressures);
  out.vector("fluid.kinds", state.kinds);
  out.value("fluid.time", state.time);
  out.value("fluid.step", static_cast<std::int64_t>(state.step));
  const PressureSetupState& setup = state.pressure_setup;
  if (!setup.kept) return;
  const std::vector<std::int32_t> counts{setup.age, setup.base_iterations, setup.last_iterations,
                                         setup.aggregate_count};
  out.vector("fluid.pressure_setup.counts", counts);
  out.vector("fluid.pressure_setup.aggregate_of_key", setup.aggregate_of_key);
  out.vector("fluid.pressure_setup.coarse_row", setup.coarse_row);
  out.vector("fluid.pressure_setup.coarse_column", setup.coarse_column);
  out.vector("fluid.pressure_setup.coarse_value", setup.coarse_value);
}

namespace {

// The aggregation set-up in reuse (schema 2 on; a checkpoint without it gets a fresh set-up).
PressureSetupState load_pressure_setup(const checkpoint::Reader& in, std::size_t particles) {
  PressureSetupState setup;
  if (!in.has("fluid.pressure_setup.counts")) return setup;
  const auto counts = in.vector<std::int32_t>("fluid.pressure_setup.counts");
  if (counts.size() != 4) {
    in.fail("fluid.pressure_setup.counts", "is not an age, two iteration counts and a size");
  }
  setup.kept = true;
  setup.age = counts[0];
  setup.base_iterations = counts[1];
  setup.last_iterations = counts[2];
  setup.aggregate_count = counts[3];
  setup.aggregate_of_key = in.vector<int>("fluid.pressure_setup.aggregate_of_key");
  setup.coarse_row = in.vector<int>("fluid.pressure_setup.coarse_row");
  setup.coarse_column = in.vector<int>("fluid.pressure_setup.coarse_column");
  setup.coarse_value = in.vector<double>("fluid.pressure_setup.coarse_value");
  if (const auto problem = find_setup_problem(setup, particles)) {
    in.fail("fluid.pressure_setup." + problem->field, problem->what);
  }
  return setup;
}

}  // namespace

MpsState load_checkpoint(const checkpoint::Reader& in) {
  // Schema 1 had no pressure set-up: it reads as one without a set-up in reuse.
  if (const auto schema = in.value<std::uint32_t>("fluid.schema");
      schema != kFluidCheckpointSchema && schema != 1) {
    in.fail("fluid.schema", "is " + std::to_string(schema) + " where this build reads 1 and " +
                                std::to_string(kFluidCheckpointSchema));
  }
  MpsState state;
  state.positions = in.vector<Eigen::Vector3d>("fluid.positions");
  state.velocities = in.vector<Eigen::Vector3d>("fluid.velocities");
  state.pressures = in.vector<double>("fluid.pressures");
  state.kinds = in.vector<ParticleKind>("fluid.kinds");
  const std::size_t n = state.positions.size();
  if (state.velocities.size() != n || state.pressures.size() != n || state.kinds.size() != n) {
    in.fail("fluid.positions", "and the other particle arrays differ in length");
  }
  for (const auto kind : state.kinds) {
    if (static_cast<int>(kind) < 0 || static_cast<int>(kind) > 3) {
      in.fail("fluid.kinds", "holds a kind outside 0-3");
    }
  }
  state.time = in.value<double>("fluid.time");
  state.step = static_cast<long>(in.value<std::int64_t>("fluid.step"));
  state.pressure_setup = load_pressure_setup(in, n);
  return state;
}

}  // namespace cosim::mps
