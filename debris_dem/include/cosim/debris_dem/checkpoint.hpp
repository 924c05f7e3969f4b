// Checkpoints of a DemWorld: every element's state, the contact list with its tangential
// springs, the fluid coupling arrays, the list-rebuild bookkeeping and the clock, so a world
// built from the same scene and loaded continues with the same bits as the one that was saved.
#pragma once

#include "cosim/checkpoint/archive.hpp"
#include "cosim/debris_dem/dem_world.hpp"

namespace cosim::dem {

// Schema of the records below; bumped when they change.
inline constexpr std::uint32_t kDemCheckpointSchema = 3;

void save_checkpoint(const DemWorld& world, checkpoint::Writer& out);
// `world` must hold the same scene (element and material counts are checked).
void load_checkpoint(DemWorld& world, const checkpoint::Reader& in);

}  // namespace cosim::dem
