// Candidate (neighbour) lists of seed 004 section 2.4(9): pairs whose bounding spheres come
// within a margin r_dam are stored and only they are tested for contact until the next reset.
#pragma once

#include <vector>

#include "cosim/debris_dem/dem_world.hpp"

namespace cosim::dem {

// Builds pairs (sorted by a, b) between elements that may touch, with their spring constants.
// Triangle pairs are grouped by moving element: group g spans
// triangle_pairs[group_start[g] .. group_start[g + 1]).
void build_candidate_pairs(const DemWorld& world, double margin, std::vector<ContactPair>& pairs,
                           std::vector<ContactPair>& triangle_pairs, std::vector<int>& group_start);

// Copies tangential spring history from the previous list into the new one (pairs matched by
// element indices; both lists sorted by a, b).
void carry_over_history(const std::vector<ContactPair>& old_pairs,
                        std::vector<ContactPair>& new_pairs);

}  // namespace cosim::dem
