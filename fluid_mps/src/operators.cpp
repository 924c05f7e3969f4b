#include "cosim/fluid_mps/operators.hpp"

namespace cosim::mps {

// Pairs at or beyond the radius are skipped, as in the fluid step, whose list is longer than
// each operator's radius.

std::vector<double> number_density(const std::vector<Eigen::Vector3d>& positions,
                                   const NeighbourList& neighbours, double radius) {
  const int n = static_cast<int>(positions.size());
  std::vector<double> result(n, 0.0);
#pragma omp parallel for schedule(static) if (n >= 4096)
  for (int i = 0; i < n; ++i) {
    double sum = 0.0;
    for (int k = neighbours.begin(i); k < neighbours.end(i); ++k) {
      if (neighbours.distance[k] < radius) sum += weight(neighbours.distance[k], radius);
    }
    result[i] = sum;
  }
  return result;
}

std::vector<Eigen::Vector3d> gradient(int dimension, const std::vector<Eigen::Vector3d>& positions,
                                      const std::vector<double>& field,
                                      const NeighbourList& neighbours, double radius, double n0) {
  const int n = static_cast<int>(positions.size());
  std::vector<Eigen::Vector3d> result(n, Eigen::Vector3d::Zero());
#pragma omp parallel for schedule(static) if (n >= 4096)
  for (int i = 0; i < n; ++i) {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (int k = neighbours.begin(i); k < neighbours.end(i); ++k) {
      const int j = neighbours.index[k];
      const double r = neighbours.distance[k];
      if (r >= radius) continue;
      sum += gradient_pair_term(field[j] - field[i], r, radius, positions[j] - positions[i]);
    }
    result[i] = gradient_factor(dimension, n0) * sum;
  }
  return result;
}

std::vector<double> divergence(int dimension, const std::vector<Eigen::Vector3d>& positions,
                               const std::vector<Eigen::Vector3d>& velocities,
                               const NeighbourList& neighbours, double radius, double n0) {
  const int n = static_cast<int>(positions.size());
  std::vector<double> result(n, 0.0);
#pragma omp parallel for schedule(static) if (n >= 4096)
  for (int i = 0; i < n; ++i) {
    double sum = 0.0;
    for (int k = neighbours.begin(i); k < neighbours.end(i); ++k) {
      const int j = neighbours.index[k];
      const double r = neighbours.distance[k];
      if (r >= radius) continue;
      sum += divergence_pair_term(velocities[j] - velocities[i], positions[j] - positions[i], r,
                                  radius);
    }
    result[i] = gradient_factor(dimension, n0) * sum;
  }
  return result;
}

std::vector<double> laplacian(int dimension, const std::vector<double>& field,
                              const NeighbourList& neighbours, double radius, double n0,
                              double lambda) {
  const int n = static_cast<int>(field.size());
  std::vector<double> result(n, 0.0);
#pragma omp parallel for schedule(static) if (n >= 4096)
  for (int i = 0; i < n; ++i) {
    double sum = 0.0;
    for (int k = neighbours.begin(i); k < neighbours.end(i); ++k) {
      if (neighbours.distance[k] >= radius) continue;
      sum += (field[neighbours.index[k]] - field[i]) * weight(neighbours.distance[k], radius);
    }
    result[i] = laplacian_factor(dimension, n0, lambda) * sum;
  }
  return result;
}

}  // namespace cosim::mps
