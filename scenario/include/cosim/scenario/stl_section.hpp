// A scenario list of STL files: each entry {stl: file relative to the scenario, scale: factor to
// metres (default 1; 0.001 for a file in mm), offset: [x, y, z] m added after scaling}. The
// files are read here, so `cosim validate` refuses a missing or malformed one at its key.
#pragma once

#include <string>
#include <vector>

#include "cosim/scenario/section.hpp"
#include "cosim/scenario/stl.hpp"

namespace cosim::scenario {

// The meshes of `section.key` (none when the key is absent), scaled and offset, each vertex
// finite. closed_for non-empty: every mesh must be a closed surface, and a failure says why
// (closed_for is the reason, e.g. "the fluid needs a solid's whole outline").
std::vector<TriangleMesh> read_stl_list(Section& section, const std::string& key,
                                        const std::string& closed_for = "");

}  // namespace cosim::scenario
