// Particle lattices and the MPS Laplacian matrix on them, for the tests of the operators and the
// pressure solvers.
#pragma once

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <vector>

#include "cosim/fluid_mps/kernels.hpp"
#include "cosim/fluid_mps/neighbour_grid.hpp"
#include "cosim/fluid_mps/pressure_solver.hpp"

namespace cosim::mps::test {

// Square (2D) or cubic (3D) lattice of side `count` particles and spacing l0 from the origin.
inline std::vector<Eigen::Vector3d> lattice(int dimension, int count, double l0) {
  std::vector<Eigen::Vector3d> points;
  for (int z = 0; z < (dimension == 3 ? count : 1); ++z)
    for (int y = 0; y < count; ++y)
      for (int x = 0; x < count; ++x) points.emplace_back(x * l0, y * l0, z * l0);
  return points;
}

inline Eigen::AlignedBox3d box_of(const std::vector<Eigen::Vector3d>& points, double margin) {
  Eigen::AlignedBox3d box;
  for (const auto& p : points) box.extend(p);
  return Eigen::AlignedBox3d(box.min().array() - margin, box.max().array() + margin);
}

// The MPS Laplacian matrix of the particles `inside` selects (their row numbers in `row_of`, -1
// outside; the others are p = 0 boundaries): diagonal sum w, off-diagonal -w to inside partners.
template <class Inside>
SparseRows kernel_laplacian(const NeighbourList& list, std::size_t particles, double radius,
                            Inside inside, std::vector<int>& row_of) {
  row_of.assign(particles, -1);
  int rows = 0;
  for (std::size_t i = 0; i < particles; ++i) {
    if (inside(static_cast<int>(i))) row_of[i] = rows++;
  }
  SparseRows a;
  for (std::size_t i = 0; i < particles; ++i) {
    if (row_of[i] < 0) continue;
    const int particle = static_cast<int>(i);
    const std::size_t diagonal = a.column.size();
    a.column.push_back(row_of[i]);
    a.value.push_back(0.0);
    for (int k = list.begin(particle); k < list.end(particle); ++k) {
      const double w = weight(list.distance[k], radius);
      a.value[diagonal] += w;
      if (row_of[list.index[k]] >= 0) {
        a.column.push_back(row_of[list.index[k]]);
        a.value.push_back(-w);
      }
    }
    a.offset.push_back(static_cast<std::int64_t>(a.column.size()));
  }
  return a;
}

// The MPS Laplacian of a cubic lattice of side `count` (spacing 1) with radius `radius`, the
// particles of the outer `ring` layers held at p = 0 (no unknowns of their own).
inline SparseRows boundary_lattice_laplacian(int count, double radius, int ring) {
  const auto points = lattice(3, count, 1.0);
  NeighbourGrid grid(3, box_of(points, 1.0), radius);
  grid.build(points);
  const NeighbourList list = grid.neighbours(points, radius);
  auto inside = [&](int i) {
    const int x = i % count, y = (i / count) % count, z = i / (count * count);
    return std::min({x, y, z}) >= ring && std::max({x, y, z}) < count - ring;
  };
  std::vector<int> row_of;
  return kernel_laplacian(list, points.size(), radius, inside, row_of);
}

// A right-hand side that varies from row to row (not an eigenvector of a lattice Laplacian).
inline std::vector<double> varying_rhs(int rows) {
  std::vector<double> b(rows);
  for (int i = 0; i < rows; ++i) b[i] = 1.0 + 0.5 * std::sin(0.37 * i);
  return b;
}

// |b - A x| / |b| (the true relative residual of x).
inline double relative_residual(const SparseRows& a, const std::vector<double>& b,
                                const std::vector<double>& x) {
  std::vector<double> ax;
  multiply(a, x, ax);
  double residual2 = 0.0, b2 = 0.0;
  for (std::size_t i = 0; i < b.size(); ++i) {
    residual2 += (b[i] - ax[i]) * (b[i] - ax[i]);
    b2 += b[i] * b[i];
  }
  return std::sqrt(residual2 / b2);
}

// The largest |x_i - y_i|; `largest` gets the largest |y_i| (the scale to compare it with).
inline double largest_difference(const std::vector<double>& x, const std::vector<double>& y,
                                 double& largest) {
  double difference = 0.0;
  largest = 0.0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    largest = std::max(largest, std::abs(y[i]));
    difference = std::max(difference, std::abs(x[i] - y[i]));
  }
  return difference;
}

}  // namespace cosim::mps::test
