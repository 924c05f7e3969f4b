// Checkpoints of a PlantField: everything that evolves (nodes, Newmark accelerations, forces
// set by the coupling, the contact candidate list and its build positions, time), so a field
// built from the same specs and loaded continues with the same bits as the one that was saved.
#pragma once

#include "cosim/checkpoint/archive.hpp"
#include "cosim/vegetation_beam/plant_field.hpp"

namespace cosim::vegetation {

// Schema of the records below; bumped when they change.
inline constexpr std::uint32_t kPlantCheckpointSchema = 1;

void save_checkpoint(const PlantField& field, checkpoint::Writer& out);
// `field` must be built from the same specs and parameters (node counts are checked).
void load_checkpoint(PlantField& field, const checkpoint::Reader& in);

}  // namespace cosim::vegetation
