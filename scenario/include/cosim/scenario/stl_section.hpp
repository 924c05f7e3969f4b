// A scenario list of STL files: each entry {stl: file relative to the scenario, scale: factor to
// metres (default 1; 0.001 for a file in mm), offset: [x, y, z] m added after scaling}. The
// files are read here, so `cosim validate` refuses a missing or malformed one at its key.
#pragma once

#include <Eigen/Core>
#include <concepts>
#include <filesystem>
#include <string>
#include <type_traits>
#include <vector>

#include "cosim/scenario/parameters.hpp"
#include "cosim/scenario/section.hpp"
#include "cosim/scenario/stl.hpp"

namespace cosim::scenario {

// One entry of such a list, declared once (parameters.hpp) for the reader and `cosim keys`.
struct StlEntryKeys {
  std::filesystem::path stl;
  double scale = 1.0;
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();
};

template <class P, class V>
requires std::same_as<std::remove_const_t<P>, StlEntryKeys>
void visit_parameters(P& p, V& v) {
  v(Key("stl").needed().doc("an ASCII or binary STL file, relative to the scenario"), p.stl);
  v(Key("scale").in(Range::positive()).doc("factor to metres (0.001 for a file in mm)"), p.scale);
  v(Key("offset").unit("m").doc("added after scaling"), p.offset);
}

// The meshes of `section.key` (none when the key is absent), scaled and offset, each vertex
// finite. closed_for non-empty: every mesh must be a closed surface, and a failure says why
// (closed_for is the reason, e.g. "the fluid needs a solid's whole outline").
std::vector<TriangleMesh> read_stl_list(Section& section, const std::string& key,
                                        const std::string& closed_for = "");

}  // namespace cosim::scenario
