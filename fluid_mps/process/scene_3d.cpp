#include "scene_3d.hpp"

#include <fmt/format.h>

#include <cmath>
#include <map>
#include <stdexcept>
#include <tuple>

#include "cosim/scenario/parameter_reader.hpp"
#include "scene_keys.hpp"

namespace cosim::mps {

namespace {

// Edges used by an odd number of triangles: 0 for a closed surface. Vertices are matched by
// their exact coordinates, as an STL exporter writes a shared vertex the same way each time.
std::size_t open_edges(const TriangleMesh& mesh) {
  using Key = std::tuple<double, double, double>;
  auto key = [](const Eigen::Vector3d& v) { return Key{v.x(), v.y(), v.z()}; };
  std::map<std::pair<Key, Key>, int> uses;
  for (const auto& t : mesh) {
    const std::array<Key, 3> v{key(t.a), key(t.b), key(t.c)};
    for (int e = 0; e < 3; ++e) {
      auto a = v[e], b = v[(e + 1) % 3];
      if (b < a) std::swap(a, b);
      ++uses[{a, b}];
    }
  }
  std::size_t odd = 0;
  for (const auto& [edge, count] : uses) odd += count % 2;
  return odd;
}

}  // namespace

std::vector<TriangleMesh> parse_stl_solids(scenario::Section& scene) {
  std::vector<TriangleMesh> solids;
  if (!scene.has("solids")) return solids;
  for (auto& entry : scene.list("solids")) {
    StlSolidKeys keys;
    scenario::read_parameters(entry, keys);  // declared in scene_keys.hpp
    const auto& file = keys.stl;
    const double scale = keys.scale;
    const Eigen::Vector3d& offset = keys.offset;
    TriangleMesh mesh;
    try {
      mesh = read_stl(file);
    } catch (const std::exception& error) {
      entry.fail("stl", error.what());
    }
    for (auto& t : mesh) {
      for (Eigen::Vector3d* v : {&t.a, &t.b, &t.c}) {
        if (!v->allFinite()) entry.fail("stl", file.string() + ": a vertex is not finite");
        *v = scale * *v + offset;
      }
    }
    if (const std::size_t open = open_edges(mesh); open > 0) {
      entry.fail("stl", fmt::format("{}: not a closed surface ({} edges belong to one triangle "
                                    "only); the fluid needs a solid's whole outline",
                                    file.string(), open));
    }
    solids.push_back(std::move(mesh));
  }
  return solids;
}

ParticleSet build_scene_3d(MpsParameters& parameters, const SceneSettings& scene) {
  const bool dam = scene.kind == "dam_break";
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
  return tank_3d(parameters, tank, {Eigen::AlignedBox3d(low, high)}, scene.solids);
}

}  // namespace cosim::mps
