// Lucy's quartic kernel (Lucy, Astron. J. 82 (1977) 1013-1024), the one smoothing kernel that
// spreads solid volumes over a neighbourhood: the fluid's solid fraction at its particles
// (fluid_mps) and the debris' local voidage (debris_dem).
#pragma once

#include <numbers>

namespace cosim::numerics {

// W(r) = C (1 + 3 q) (1 - q)^3, q = r / R < 1, 0 beyond; C normalises it to unit integral over
// the plane (5 / (pi R^2)) or space (105 / (16 pi R^3)). Zero slope at 0 and R, so a volume
// enters and leaves the average smoothly as it moves. Units: 1 / R^dimension.
inline double lucy_kernel(double distance, double radius, int dimension) {
  const double q = distance / radius;
  if (q >= 1.0) return 0.0;
  const double one_minus = 1.0 - q;
  const double shape = (1.0 + 3.0 * q) * one_minus * one_minus * one_minus;
  const double norm = dimension == 2 ? 5.0 / (std::numbers::pi * radius * radius)
                                     : 105.0 / (16.0 * std::numbers::pi * radius * radius * radius);
  return norm * shape;
}

}  // namespace cosim::numerics
