#include "cosim/fluid_mps/operators.hpp"

#include "cosim/fluid_mps/kernels.hpp"

namespace cosim::mps {

std::vector<double> number_density(const std::vector<Eigen::Vector3d>& positions,
                                   const NeighbourList& neighbours, double radius) {
  const int n = static_cast<int>(positions.size());
  std::vector<double> result(n, 0.0);
#pragma omp parallel for schedule(static) if (n >= 4096)
  for (int i = 0; i < n; ++i) {
    double sum = 0.0;
    for (int k = neighbours.begin(i); k < neighbours.end(i); ++k) {
      sum += weight(neighbours.distance[k], radius);
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
      sum += (field[j] - field[i]) / (r * r) * weight(r, radius) * (positions[j] - positions[i]);
    }
    result[i] = dimension / n0 * sum;
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
      sum += (field[neighbours.index[k]] - field[i]) * weight(neighbours.distance[k], radius);
    }
    result[i] = 2.0 * dimension / (lambda * n0) * sum;
  }
  return result;
}

}  // namespace cosim::mps
