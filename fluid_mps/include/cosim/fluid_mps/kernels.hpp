// MPS weight function and the lattice constants n0 and lambda.
#pragma once

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

}  // namespace cosim::mps
