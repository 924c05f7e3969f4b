#include "scene_3d.hpp"

#include <fmt/format.h>

#include <cmath>
#include <stdexcept>
#include <utility>

#include "cosim/scenario/stl_section.hpp"

namespace cosim::mps {

using scenario::Range;

std::vector<TriangleMesh> parse_stl_solids(scenario::Section& scene) {
  return scenario::read_stl_list(scene, "solids", "the fluid needs a solid's whole outline");
}

bool is_flume_scene(scenario::Section& scene) {
  return scene.has("kind") && scene.text("kind") == "flume";
}

SceneSettings parse_flume_scene(scenario::Section& scene, int dimension, double spacing) {
  SceneSettings s;
  s.kind = scene.choice("kind", {"flume"});
  if (dimension != 3) {
    scene.fail("kind",
               "'flume' is a 3D scene: it needs dimension: 3 (a 2D sloping channel is "
               "open_channel or periodic_channel)");
  }
  // The same three keys as the debris_dem flume, so one YAML anchor can give both the numbers.
  s.tank_length = scene.number("length", Range::positive());
  s.tank_width = scene.number("width", Range::positive());
  s.tank_height = scene.number("wall_height", Range::positive());
  auto water = scene.child("water");
  s.column_x = water.number("x_min", 0.0, Range::non_negative());
  const double x_max = water.number("x_max", Range::positive());
  if (x_max <= s.column_x) water.fail("x_max", "must exceed x_min");
  if (x_max > s.tank_length + 1e-12) water.fail("x_max", "the water ends beyond the flume");
  s.column_width = x_max - s.column_x;
  s.column_height = water.number("depth", Range::positive());
  if (s.column_height > s.tank_height) water.fail("depth", "exceeds the flume's wall_height");
  if (scene.has("outlet_x")) {
    s.outlet_x = scene.number("outlet_x", Range::positive());
    if (s.outlet_x <= x_max || s.outlet_x >= s.tank_length) {
      scene.fail("outlet_x", "must lie between the water's x_max and the flume's end");
    }
  }
  s.solids = parse_stl_solids(scene);
  s.wall_layers = scene.integer("wall_layers", s.wall_layers, Range::between(1, 10));
  s.dummy_layers = scene.integer("dummy_layers", s.dummy_layers, Range::between(0, 10));
  // tank_3d rounds each size to whole cells l0; a face off the lattice would move the fluid's
  // wall away from the DEM's by up to l0 / 2, so the sizes must be whole cells (1e-6 relative).
  for (const auto& [key, size] :
       {std::pair{"length", s.tank_length}, std::pair{"width", s.tank_width},
        std::pair{"wall_height", s.tank_height}}) {
    const double cells = size / spacing;
    if (std::lround(cells) < 1 || std::abs(cells - std::round(cells)) > 1e-6 * cells) {
      scene.fail(key, fmt::format("{} m is not a whole number of particle_spacing {} m cells: "
                                  "the fluid's walls would not stand where the debris' do",
                                  size, spacing));
    }
  }
  return s;
}

ParticleSet build_scene_3d(MpsParameters& parameters, const SceneSettings& scene) {
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
