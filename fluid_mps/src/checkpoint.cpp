#include "cosim/fluid_mps/checkpoint.hpp"

namespace cosim::mps {

void save_checkpoint(const FluidSystem& system, checkpoint::Writer& out) {
  const MpsState state = system.save_state();
  out.value("fluid.schema", kFluidCheckpointSchema);
  out.value("fluid.dimension", system.parameters().dimension);
  out.vector("fluid.positions", state.positions);
  out.vector("fluid.velocities", state.velocities);
  out.vector("fluid.pressures", state.pressures);
  out.vector("fluid.kinds", state.kinds);
  out.value("fluid.time", state.time);
  out.value("fluid.step", static_cast<std::int64_t>(state.step));
}

MpsState load_checkpoint(const checkpoint::Reader& in) {
  if (const auto schema = in.value<std::uint32_t>("fluid.schema");
      schema != kFluidCheckpointSchema) {
    in.fail("fluid.schema", "is " + std::to_string(schema) + " where this build reads " +
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
  return state;
}

}  // namespace cosim::mps
