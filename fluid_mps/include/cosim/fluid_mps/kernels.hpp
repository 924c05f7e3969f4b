// MPS weight function and the lattice constants n0 and lambda.
#pragma once

#include <Eigen/Core>

namespace cosim::mps {

// Weight function w(r) = re/r - 1 for r < re, else 0 (seed 000 eq. (6), seed 001 eq. (5)).
inline double weight(double distance, double radius) {
  return distance < radius && distance > 0.0 ? radius / distance - 1.0 : 0.0;
}

// Constants of a full square (2D) or cubic (3D) lattice of spacing l0 around one particle.
struct LatticeSums {
  double n0 = 0.0;                // particle number density, seed 001 eq. (7); independent of l0
  double lambda_over_l0sq = 0.0;  // lambda / l0^2, seed 000 eq. (4)
  int neighbour_count = 0;        // lattice points with 0 < r < re
};

// Sums over the lattice points j != i with |r_ij| < radius_over_l0 * l0 (seed 001: n0 is taken
// from the initial arrangement of a particle with no free surface inside r_e).
LatticeSums lattice_sums(int dimension, double radius_over_l0);

// The same sums on a face-centred cubic lattice with l0^3 per particle (MpsParameters::
// FillLattice::fcc): the sites (i, j, k) h with i + j + k even, h = 2^(-1/3) l0 the spacing of
// its (100) layers, each axis's spacing times `stretch` (the fill fitted to a tank).
LatticeSums fcc_lattice_sums(double radius_over_l0, const Eigen::Vector3d& stretch);

// The fcc layer spacing h / l0 = 2^(-1/3): 2 h^3 = l0^3 (half the sites of the cubic grid h).
inline double fcc_layer_spacing_over_l0() {
  return 0.7937005259840998;
}

}  // namespace cosim::mps
