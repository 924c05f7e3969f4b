// MPS particle interaction models on arbitrary particle sets (seed 001 eqs. (7)-(9)). The fluid
// step uses the same formulas inline; these free functions exist for tests and post-processing.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "cosim/fluid_mps/neighbour_grid.hpp"

namespace cosim::mps {

// n_i = sum_{j != i} w(|r_ij|) with radius re (seed 001 eq. (7)).
std::vector<double> number_density(const std::vector<Eigen::Vector3d>& positions,
                                   const NeighbourList& neighbours, double radius);

// <grad phi>_i = d/n0 sum (phi_j - phi_i) r_ij / |r_ij|^2 w(|r_ij|) (seed 001 eq. (8)).
std::vector<Eigen::Vector3d> gradient(int dimension, const std::vector<Eigen::Vector3d>& positions,
                                      const std::vector<double>& field,
                                      const NeighbourList& neighbours, double radius, double n0);

// <lap phi>_i = 2d/(lambda n0) sum (phi_j - phi_i) w(|r_ij|) (seed 001 eq. (9)).
std::vector<double> laplacian(int dimension, const std::vector<double>& field,
                              const NeighbourList& neighbours, double radius, double n0,
                              double lambda);

}  // namespace cosim::mps
