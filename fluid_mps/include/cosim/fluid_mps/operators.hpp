// MPS particle interaction models (seed 001 eqs. (7)-(9)). The pair terms below are the ones the
// fluid step sums (fluid_step.cpp); the free functions apply them to arbitrary particle sets for
// tests and post-processing, so the tested operators are the operators that run.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "cosim/fluid_mps/kernels.hpp"
#include "cosim/fluid_mps/neighbour_grid.hpp"

namespace cosim::mps {

// Pair term of the gradient model: (phi_j - phi_i) r_ij / |r_ij|^2 w(|r_ij|) (seed 001 eq. (8)).
inline Eigen::Vector3d gradient_pair_term(double difference, double distance, double radius,
                                          const Eigen::Vector3d& offset) {
  return difference / (distance * distance) * weight(distance, radius) * offset;
}

// Pair term of the divergence model: (u_j - u_i) . r_ij / |r_ij|^2 w(|r_ij|) (eq. (8) applied
// to u . r_ij).
inline double divergence_pair_term(const Eigen::Vector3d& velocity_difference,
                                   const Eigen::Vector3d& offset, double distance, double radius) {
  return velocity_difference.dot(offset) / (distance * distance) * weight(distance, radius);
}

// Factors in front of the sums: d / n0 (gradient, divergence), 2d / (lambda n0) (Laplacian).
inline double gradient_factor(int dimension, double n0) {
  return dimension / n0;
}
inline double laplacian_factor(int dimension, double n0, double lambda) {
  return 2.0 * dimension / (lambda * n0);
}

// n_i = sum_{j != i} w(|r_ij|) with radius re (seed 001 eq. (7)).
std::vector<double> number_density(const std::vector<Eigen::Vector3d>& positions,
                                   const NeighbourList& neighbours, double radius);

// <grad phi>_i = d/n0 sum (phi_j - phi_i) r_ij / |r_ij|^2 w(|r_ij|) (seed 001 eq. (8)).
std::vector<Eigen::Vector3d> gradient(int dimension, const std::vector<Eigen::Vector3d>& positions,
                                      const std::vector<double>& field,
                                      const NeighbourList& neighbours, double radius, double n0);

// <div u>_i = d/n0 sum (u_j - u_i) . r_ij / |r_ij|^2 w(|r_ij|).
std::vector<double> divergence(int dimension, const std::vector<Eigen::Vector3d>& positions,
                               const std::vector<Eigen::Vector3d>& velocities,
                               const NeighbourList& neighbours, double radius, double n0);

// <lap phi>_i = 2d/(lambda n0) sum (phi_j - phi_i) w(|r_ij|) (seed 001 eq. (9)).
std::vector<double> laplacian(int dimension, const std::vector<double>& field,
                              const NeighbourList& neighbours, double radius, double n0,
                              double lambda);

}  // namespace cosim::mps
