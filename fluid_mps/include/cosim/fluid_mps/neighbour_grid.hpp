// Cell-linked neighbour search, O(N): particles are counting-sorted into cubic cells of the
// search radius, so each particle only tests the 3^D surrounding cells.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <vector>

#include "cosim/fluid_mps/parameters.hpp"

namespace cosim::mps {

// Compressed neighbour lists: the neighbours of i are index[offset[i] .. offset[i+1]) with their
// distances, in a fixed order (cell by cell, then by particle index), so every loop over them is
// deterministic whatever the number of OpenMP threads.
struct NeighbourList {
  std::vector<std::int64_t> offset;
  std::vector<int> index;
  std::vector<double> distance;
  double radius = 0.0;

  int begin(int i) const { return static_cast<int>(offset[i]); }
  int end(int i) const { return static_cast<int>(offset[i + 1]); }
  std::size_t pair_count() const { return index.size(); }
};

// Box around the positions (with `include`, those with include[i] != 0) grown by `margin`; in
// 2D the z extent is [-margin, margin]. Grids are built on this box rather than the whole domain
// so memory follows the particles.
Eigen::AlignedBox3d bounding_box(const std::vector<Eigen::Vector3d>& positions, int dimension,
                                 double margin, const std::vector<char>* include = nullptr);

// Work arrays of NeighbourGrid::neighbours_by_key kept between searches: their capacity stays,
// so a search after the first allocates nothing and touches no fresh pages (each search used to
// grow one pair buffer a thread from empty, zero-filling every candidate's slot on the way).
struct NeighbourSearchWork {
  std::vector<std::vector<int>> thread_index;  // one thread's rows, in its cells' order (the
                                               // size is the capacity, never shrunk)
  std::vector<std::int64_t> segment;           // where row i starts in its thread's buffer
  std::vector<int> owner;                      // the thread that found row i
  std::vector<std::int64_t> wanted_start;      // rows before each cell (with a row mask)
};

class NeighbourGrid {
 public:
  // `box` must contain every position (the caller checks escapes first); 2D uses one z layer.
  // With an enabled `periodic` boundary the x extent is [x_min, x_max) whatever the box, cells
  // wrap around in x (at least 3 cells, so the cell size may grow to period / floor(period /
  // cell_size)) and distances are minimum-image distances across the seam.
  NeighbourGrid(int dimension, const Eigen::AlignedBox3d& box, double cell_size,
                const PeriodicBoundary& periodic = PeriodicBoundary{});

  // Sorts the particles into cells. With `include`, particles with include[i] == 0 are left out:
  // they are nobody's neighbour and have no neighbours themselves.
  void build(const std::vector<Eigen::Vector3d>& positions,
             const std::vector<char>* include = nullptr);

  // All pairs j != i with |r_j - r_i| < radius (radius <= cell size). Parallel and deterministic.
  NeighbourList neighbours(const std::vector<Eigen::Vector3d>& positions, double radius) const;

  // The same pairs, each particle's partners in ascending key[j] (keys distinct, e.g. the
  // particle ids of particles stored in another order), written into `list` (its storage is
  // reused) without distances. Built cell by cell: the particles of the 3^D cells around a cell
  // are gathered once, sorted by key and tested against each particle of the cell, so no
  // per-particle sort is needed. Parallel; the same list whatever the thread count. With `rows`
  // (one entry a particle), a particle with rows[i] == 0 gets an empty row of its own but is
  // still a partner of the others: the rows of every other particle are those without `rows`.
  // `work` (optional) keeps the work arrays for the next search.
  void neighbours_by_key(const std::vector<Eigen::Vector3d>& positions, double radius,
                         const std::vector<int>& key, NeighbourList& list,
                         const std::vector<char>* rows = nullptr,
                         NeighbourSearchWork* work = nullptr) const;

  // Included particles cell by cell (cells in memory order, z slowest), each cell's in index
  // order: an order along the cells for memory locality.
  const std::vector<int>& cell_order() const { return sorted_; }

  // Particles within `radius` of an arbitrary point (radius may exceed the cell size).
  void query(const std::vector<Eigen::Vector3d>& positions, const Eigen::Vector3d& point,
             double radius, std::vector<int>& found) const;

  double cell_size() const { return cell_size_; }
  const PeriodicBoundary& periodic() const { return periodic_; }

 private:
  Eigen::Array3i cell_of(const Eigen::Vector3d& position) const;
  std::int64_t linear(const Eigen::Array3i& cell) const {
    return (static_cast<std::int64_t>(cell.z()) * cells_.y() + cell.y()) * cells_.x() + cell.x();
  }
  // The cell of linear index c (the inverse of linear()).
  Eigen::Array3i cell_at(std::int64_t c) const {
    return {static_cast<int>(c % cells_.x()), static_cast<int>((c / cells_.x()) % cells_.y()),
            static_cast<int>(c / (static_cast<std::int64_t>(cells_.x()) * cells_.y()))};
  }
  // Visits the cells low..high (y, z) and the x cells of `xs` (already wrapped).
  template <class Visit>
  void visit_cells(const std::vector<int>& xs, const Eigen::Array3i& low,
                   const Eigen::Array3i& high, Visit&& visit) const;
  // Cells searched around `cell` (the 3^D block, extended in y across a seam with a drop).
  void search_block(const Eigen::Array3i& cell, std::vector<int>& xs, Eigen::Array3i& low,
                    Eigen::Array3i& high) const;
  // Candidates in key order: positions by coordinate, and particle indices.
  struct CandidateSpan {
    const double *x, *y, *z;
    const int* j;
    std::size_t count;
  };
  // Work arrays of neighbours_by_key, one set a thread.
  struct KeyedScratch {
    std::vector<std::uint64_t> candidate;  // key << 32 | particle, sorted
    std::vector<std::uint64_t> sorted;     // the sort's second buffer
    std::vector<double> cx, cy, cz;        // their positions, in that order
    std::vector<int> cj;                   // and indices
    std::vector<double> distance2;
    std::vector<int> xs;
    // The cell split in 2^D parts (narrow_to_parts): each part's candidates, part after part.
    std::vector<double> px, py, pz;
    std::vector<int> pj;
    std::array<std::size_t, 9> part_begin{};
    std::vector<unsigned char> part_of;  // the part of each particle of the cell
  };
  void gather_candidates(std::int64_t c, const std::vector<Eigen::Vector3d>& positions,
                         const std::vector<int>& key, KeyedScratch& s) const;
  bool narrow_to_parts(std::int64_t c, const std::vector<Eigen::Vector3d>& positions,
                       double radius2, KeyedScratch& s) const;
  std::size_t candidates_in_reach(int i, const Eigen::Vector3d& xi, double radius2,
                                  const CandidateSpan& span, double* distance2, int* out) const;
  // x cells within `reach` of cell x, wrapped when periodic, each once, in ascending order.
  void x_range(int x, int reach, std::vector<int>& xs) const;
  // Extra y cells to search: across a seam with a drop, neighbours are stored up to `drop`
  // higher or lower.
  int drop_cells() const;

  int dimension_;
  Eigen::Vector3d origin_;
  double cell_size_;
  Eigen::Array3i cells_;
  std::vector<std::int64_t> cell_start_;  // size cell count + 1
  std::vector<int> sorted_;               // particle indices ordered by cell, then index
  std::vector<char> included_;            // empty: all particles
  PeriodicBoundary periodic_;
};

}  // namespace cosim::mps
