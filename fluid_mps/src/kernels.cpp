#include "cosim/fluid_mps/kernels.hpp"

#include <Eigen/Geometry>
#include <array>
#include <cmath>
#include <stdexcept>

namespace cosim::mps {

LatticeSums lattice_sums(int dimension, double radius_over_l0) {
  if (dimension != 2 && dimension != 3) {
    throw std::invalid_argument("lattice_sums: dimension must be 2 or 3");
  }
  const int reach = static_cast<int>(std::ceil(radius_over_l0));
  const int z_reach = dimension == 3 ? reach : 0;
  LatticeSums sums;
  double weighted_r2 = 0.0;
  for (int z = -z_reach; z <= z_reach; ++z)
    for (int y = -reach; y <= reach; ++y)
      for (int x = -reach; x <= reach; ++x) {
        const double r = std::sqrt(static_cast<double>(x * x + y * y + z * z));
        if (r == 0.0 || r >= radius_over_l0) continue;
        const double w = weight(r, radius_over_l0);
        sums.n0 += w;
        weighted_r2 += w * r * r;
        ++sums.neighbour_count;
      }
  // seed 000 eq. (4): lambda = sum w r^2 / sum w
  sums.lambda_over_l0sq = sums.n0 > 0.0 ? weighted_r2 / sums.n0 : 0.0;
  return sums;
}

LatticeSums fcc_lattice_sums(double radius_over_l0, const Eigen::Vector3d& stretch) {
  const Eigen::Vector3d h = fcc_layer_spacing_over_l0() * stretch;
  std::array<int, 3> reach{};
  for (int d = 0; d < 3; ++d) reach[d] = static_cast<int>(std::ceil(radius_over_l0 / h[d]));
  LatticeSums sums;
  double weighted_r2 = 0.0;
  for (int z = -reach[2]; z <= reach[2]; ++z)
    for (int y = -reach[1]; y <= reach[1]; ++y)
      for (int x = -reach[0]; x <= reach[0]; ++x) {
        if ((x + y + z) % 2 != 0) continue;  // the fcc sites of the cubic grid h
        const double r = Eigen::Vector3d(x * h[0], y * h[1], z * h[2]).norm();
        if (r == 0.0 || r >= radius_over_l0) continue;
        const double w = weight(r, radius_over_l0);
        sums.n0 += w;
        weighted_r2 += w * r * r;
        ++sums.neighbour_count;
      }
  sums.lambda_over_l0sq = sums.n0 > 0.0 ? weighted_r2 / sums.n0 : 0.0;  // seed 000 eq. (4)
  return sums;
}

}  // namespace cosim::mps
