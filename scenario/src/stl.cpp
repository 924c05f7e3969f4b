#include "cosim/scenario/stl.hpp"

#include <array>
#include <cstdint>
#include <fstream>
#include <map>
#include <stdexcept>
#include <string>
#include <tuple>

namespace cosim::scenario {
namespace {

float read_float(std::istream& in) {
  float value = 0.0f;
  in.read(reinterpret_cast<char*>(&value), sizeof value);
  return value;
}

}  // namespace

TriangleMesh read_stl(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw std::runtime_error("read_stl: cannot open " + file.string());
  // Binary: an 80-byte header, a triangle count, then 50 bytes a triangle (normal, 3 vertices
  // as float32, 2 attribute bytes). Anything of another size is read as ASCII.
  char header[80] = {};
  std::uint32_t count = 0;
  in.read(header, sizeof header);
  in.read(reinterpret_cast<char*>(&count), sizeof count);
  const auto size = std::filesystem::file_size(file);
  TriangleMesh mesh;
  if (in && size == 84 + 50ull * count) {
    for (std::uint32_t i = 0; i < count; ++i) {
      std::array<Eigen::Vector3d, 4> v;  // normal, then the three vertices
      for (auto& x : v) {
        for (int k = 0; k < 3; ++k) x[k] = read_float(in);  // in order: x, y, z
      }
      in.ignore(2);
      mesh.push_back({v[1], v[2], v[3]});
    }
    return mesh;
  }
  in.clear();
  in.seekg(0);
  std::vector<Eigen::Vector3d> vertices;
  std::string word;
  while (in >> word) {
    if (word != "vertex") continue;
    Eigen::Vector3d x;
    if (!(in >> x.x() >> x.y() >> x.z())) {
      throw std::runtime_error("read_stl: " + file.string() + ": bad vertex");
    }
    vertices.push_back(x);
  }
  if (vertices.empty() || vertices.size() % 3 != 0) {
    throw std::runtime_error("read_stl: " + file.string() + ": no triangles (or a broken one)");
  }
  for (std::size_t i = 0; i < vertices.size(); i += 3) {
    mesh.push_back({vertices[i], vertices[i + 1], vertices[i + 2]});
  }
  return mesh;
}

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

}  // namespace cosim::scenario
