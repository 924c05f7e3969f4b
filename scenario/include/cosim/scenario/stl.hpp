// Triangle surfaces from STL files, shared by the solvers that take walls from triangles: the
// MPS fluid (closed solids whose inside is wall) and the DEM (each triangle a fixed wall
// element), so both can be given the same file and see the same walls.
#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <vector>

namespace cosim::scenario {

struct Triangle {
  Eigen::Vector3d a, b, c;
};
using TriangleMesh = std::vector<Triangle>;

// ASCII or binary STL, coordinates as written (scale them afterwards if the file is in mm).
// Throws std::runtime_error naming the file for a missing, empty or broken one.
TriangleMesh read_stl(const std::filesystem::path& file);

// Edges used by an odd number of triangles: 0 for a closed surface. Vertices are matched by
// their exact coordinates, as an STL exporter writes a shared vertex the same way each time.
std::size_t open_edges(const TriangleMesh& mesh);

}  // namespace cosim::scenario
