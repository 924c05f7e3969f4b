#include "scene_3d.hpp"

#include <fmt/format.h>

#include <cmath>
#include <stdexcept>
#include <utility>

#include "cosim/scenario/stl_section.hpp"

namespace cosim::mps {

std::vector<TriangleMesh> parse_stl_solids(scenario::Section& scene) {
  return scenario::read_stl_list(scene, "solids", "the fluid needs a solid's whole outline");
}

ParticleSet build_scene_3d(MpsParameters& parameters, SceneSettings& scene) {
  const Channel3d channel{scene.tank_width, scene.tank_height, scene.wall_layers,
                          scene.dummy_layers};
  // The bed slope is the world's gravity tilt, as in 2D.
  if (scene.kind == "periodic_channel") {
    return periodic_channel_3d(parameters, channel, scene.length, scene.depth);
  }
  if (scene.kind == "open_channel") {
    return open_channel_3d(parameters, scene.inflow, channel, scene.length, scene.depth,
                           scene.block_height, scene.block_columns, scene.pool_particles);
  }
  // A flume is a tank whose water is a reservoir at its upstream end: the column of a dam break.
  const bool dam = scene.kind == "dam_break" || scene.kind == "flume";
  if (!dam && scene.kind != "still_water_tank") {
    throw std::invalid_argument("build_scene_3d: no 3D scene of kind " + scene.kind);
  }
  const Tank3d tank{dam ? scene.tank_length : scene.width,
                    scene.tank_width,
                    scene.tank_height,
                    scene.obstacles,
                    scene.wall_layers,
                    scene.dummy_layers};
  const Eigen::Vector3d low(dam ? scene.column_x : 0.0, 0.0, 0.0);
  const Eigen::Vector3d high = dam ? Eigen::Vector3d(scene.column_x + scene.column_width,
                                                     scene.tank_width, scene.column_height)
                                   : Eigen::Vector3d(scene.width, scene.tank_width, scene.depth);
  if (scene.kind == "flume" && parameters.domain.isEmpty()) {
    // As tank_3d's domain, with four wall heights of headroom instead of two: the surge that
    // meets the end wall runs up it (u^2 / 2g ~ 0.5 m at 3 m/s) before falling back.
    const double margin =
        (scene.wall_layers + scene.dummy_layers + 2) * parameters.particle_spacing;
    parameters.domain =
        Eigen::AlignedBox3d(Eigen::Vector3d(-margin, -margin, -margin),
                            Eigen::Vector3d(scene.tank_length + margin, scene.tank_width + margin,
                                            4.0 * scene.tank_height));
  }
  return tank_3d(parameters, tank, {Eigen::AlignedBox3d(low, high)}, scene.solids);
}

}  // namespace cosim::mps
