// The debris scene as the process builds it from its configuration, and its output frames.
#pragma once

#include <filesystem>
#include <vector>

#include "cosim/debris_dem/dem_world.hpp"
#include "cosim/output/point_series.hpp"
#include "dem_config.hpp"

namespace cosim::dem {

struct BuiltScene {
  Packing packing;
  std::vector<int> explicit_elements;  // the `elements:` list, in order
  double sphere_volume = 0.0;
  double log_volume = 0.0;
  double settle_seconds = 0.0;  // wall time of the settling behind the gate
};

// The structure, the packing (settled behind its gate, which is then removed) and the explicit
// elements.
BuiltScene build_scene(DemWorld& world, const DebrisConfig& config);

// Moving elements with their window-mean fluid force, submerged share and local voidage.
output::PointFrame make_frame(const DemWorld& world, const std::vector<int>& elements);

// The fixed elements and the triangles of the structure, as two frames of `stem`.
void write_structure(const DemWorld& world, const std::filesystem::path& stem);

}  // namespace cosim::dem
