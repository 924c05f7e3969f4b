// The pressure unknowns numbered along space: by cell of a grid over their own box, the box's
// longest axis slowest, particles of one cell in the order given (particle id order). The
// numbering is a function of the positions and the given order alone, so a restarted run, whose
// internal particle order differs from the straight run's, numbers its rows as the straight run
// does and keeps its bits; and rows of particles that are neighbours in space are near in
// number, so the CG product's gathers of x and the assembly's reads of the pair lists stay in
// cache (docs/performance.md, "The pressure unknowns numbered along space").
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

namespace cosim::mps {

struct SpatialOrderWork {  // kept between calls: no allocation once grown
  std::vector<std::uint64_t> key, key_scratch;
  std::vector<int> item_scratch;
  std::vector<int> count;
};

// Reorders `items` (indices into `positions`) by the cell of size `cell_size` holding each
// position (2D: the x-z plane), cells in memory order of a grid whose slowest axis is the box's
// longest; items of one cell keep their relative order (a stable sort). Positions must be finite.
void order_along_cells(const std::vector<Eigen::Vector3d>& positions, double cell_size,
                       int dimension, std::vector<int>& items, SpatialOrderWork& work);

}  // namespace cosim::mps
