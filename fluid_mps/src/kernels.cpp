#include "cosim/fluid_mps/kernels.hpp"

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

}  // namespace cosim::mps
