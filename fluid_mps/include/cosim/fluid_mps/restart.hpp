// Restart files: the MpsState of a FluidSystem in a small binary format (little-endian host
// layout, versioned header). Doubles are written bit for bit, so a restarted run continues
// exactly like a straight one.
#pragma once

#include <string>

#include "cosim/fluid_mps/fluid_system.hpp"

namespace cosim::mps {

void save_state(const FluidSystem& system, const std::string& path);
void save_state(const MpsState& state, const std::string& path);
MpsState load_state(const std::string& path);

}  // namespace cosim::mps
