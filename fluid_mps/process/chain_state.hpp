// `scene.chain_state` of a periodic_pool scene: the frame of a pool_fishway run it starts from,
// read and checked when the scenario is read (so `cosim validate` refuses a bad one at its key).
#pragma once

#include <optional>

#include "cosim/fluid_mps/fluid_system.hpp"
#include "cosim/scenario/section.hpp"
#include "fluid_config.hpp"

namespace cosim::mps {

// The periodic pool's first state from `scene.chain_state` (none when the key is absent or
// null: the pool starts level). `config` holds the parameters and the scene already read.
std::optional<MpsState> parse_chain_state(scenario::Section& scene, const FluidConfig& config);

}  // namespace cosim::mps
