// The 3D scenes of the fluid_mps section: a tank (scenes.hpp, tank_3d) holding a dam-break column
// or still water, with the scenario's obstacle boxes and STL solids, or a channel.
#pragma once

#include "cosim/scenario/section.hpp"
#include "fluid_config.hpp"

namespace cosim::mps {

// `solids` of a 3D scene: each entry {stl: file relative to the scenario, scale: factor to metres
// (default 1; 0.001 for a file in mm), offset: [x, y, z] m added after scaling}
// (cosim/scenario/stl_section.hpp, as debris_dem's `walls`). The file is read and checked here (a
// closed surface: every edge shared by an even number of triangles), so validate refuses a
// missing, malformed or open one at its key.
std::vector<TriangleMesh> parse_stl_solids(scenario::Section& scene);

// dam_break (and flume): the column [column_x, column_x + column_width] over the whole width,
// column_height high; still_water_tank: `width` long (x), filled to `depth`. Water cells inside an
// obstacle or a solid are solid. periodic_channel and open_channel: the 3D channels of
// boundaries.hpp, tank_width wide with side walls tank_height high (open_channel fills
// scene.inflow's geometry).
ParticleSet build_scene_3d(MpsParameters& parameters, SceneSettings& scene);

}  // namespace cosim::mps
