// Checkpoints of a FluidSystem: its MpsState (positions, velocities, pressures, kinds, time,
// step count, and the pressure solver's set-up in reuse) as records of a checkpoint file. The
// forces and solid volumes of the coupling are set again at the start of every window, and the pair
// list and multigrid hierarchy are rebuilt without changing the sums (fluid_system.hpp), so
// FluidSystem(parameters, state) continues with the same bits as the saved system.
#pragma once

#include "cosim/checkpoint/archive.hpp"
#include "cosim/fluid_mps/fluid_system.hpp"

namespace cosim::mps {

// Schema of the records below; bumped when they change.
inline constexpr std::uint32_t kFluidCheckpointSchema = 2;  // 2: the pressure set-up in reuse

void save_checkpoint(const FluidSystem& system, checkpoint::Writer& out);
void save_checkpoint(const MpsState& state, int dimension, checkpoint::Writer& out);
// Throws checkpoint::Error naming the file and record when the state does not fit `parameters`
// (another dimension) or is inconsistent.
MpsState load_checkpoint(const checkpoint::Reader& in);

}  // namespace cosim::mps
