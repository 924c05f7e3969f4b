#include "cosim/scenario/stl_section.hpp"

#include "cosim/scenario/parameter_reader.hpp"

#include <fmt/format.h>

#include <exception>

namespace cosim::scenario {

std::vector<TriangleMesh> read_stl_list(Section& section, const std::string& key,
                                        const std::string& closed_for) {
  std::vector<TriangleMesh> meshes;
  if (!section.has(key)) return meshes;
  for (auto& entry : section.list(key)) {
    StlEntryKeys keys;
    read_parameters(entry, keys);
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
    if (!closed_for.empty()) {
      if (const std::size_t open = open_edges(mesh); open > 0) {
        entry.fail("stl", fmt::format("{}: not a closed surface ({} edges belong to one "
                                      "triangle only); {}",
                                      file.string(), open, closed_for));
      }
    }
    meshes.push_back(std::move(mesh));
  }
  return meshes;
}

}  // namespace cosim::scenario
