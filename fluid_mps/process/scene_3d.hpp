// The 3D scenes of the fluid_mps section: a tank (scenes.hpp, tank_3d) holding a dam-break column
// or still water, with the scenario's obstacle boxes and STL solids.
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

// kind: flume (3D only), a straight channel for a debris flow: bed z = 0 over x in [0, length],
// side walls at y = 0 and y = width, end walls at x = 0 and x = length, all wall_height high
// (the debris_dem flume's keys, with its upstream_wall and downstream_wall), and a reservoir of
// water `water: {x_min (default 0), x_max, depth}` across the whole width, at rest until t = 0.
// The slope is the world's (world.slope_degrees: x along the bed, gravity tilted,
// docs/architecture.md), so the bed is flat in the solver's coordinates and its walls lie on the
// lattice, where the DEM's triangles are. Optional `outlet_x`: fluid past it leaves the flow (the
// water running off a flume's end: the end wall behind it is only the lattice's edge, and the
// surge never slams into it), `solids` (STL), wall_layers, dummy_layers.
// The sizes must be whole cells of particle_spacing (a face off the lattice would stand up to
// l0 / 2 from the DEM's wall).
bool is_flume_scene(scenario::Section& scene);  // kind: flume
SceneSettings parse_flume_scene(scenario::Section& scene, int dimension, double spacing);

// dam_break (and flume): the column [column_x, column_x + column_width] over the whole width,
// column_height high; still_water_tank: `width` long (x), filled to `depth`. Water cells inside an
// obstacle or a solid are solid.
ParticleSet build_scene_3d(MpsParameters& parameters, const SceneSettings& scene);

}  // namespace cosim::mps
