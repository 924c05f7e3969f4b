// Closed forms behind the unresolved fluid forces of DemWorld (dem_fluid.cpp): the submerged
// share of a sphere or a cylinder below a flat free surface, drag correlations, the Di Felice
// voidage exponent and the kernel estimate of the local fluid volume fraction. Free functions,
// so tests and the process can use them directly.
#pragma once

#include <Eigen/Dense>
#include <vector>

namespace cosim::dem {

// Share (0..1) of a sphere's volume below the plane z = surface_z (world z up): the spherical
// cap V = pi h^2 (3 r - h) / 3 with h = surface_z - (center_z - r) clamped to [0, 2 r].
double sphere_submerged_fraction(double center_z, double radius, double surface_z);

// Share (0..1) of a flat-ended cylinder's volume (any axis orientation) below the plane
// z = surface_z, exact: sliced normal to the axis each slice is a disk cut by a chord (circular
// segment), and the segment area integrates in closed form along the axis (see the .cpp).
double cylinder_submerged_fraction(const Eigen::Vector3d& center, const Eigen::Vector3d& axis_unit,
                                   double radius, double length, double surface_z);

// Sphere drag coefficient of Schiller & Naumann, Z. Ver. Dtsch. Ing. 77 (1933) 318-320:
// C_D = 24/Re (1 + 0.15 Re^0.687) for Re < 1000, 0.44 above (Re = rho |u - v| d / mu > 0).
double schiller_naumann_drag_coefficient(double reynolds);

// Drag coefficient of a long circular cylinder in crossflow, per projected area D L:
// C_D = 1 + 10 Re^(-2/3), the fit of White, Viscous Fluid Flow (3rd ed., 2006) to the data for
// 1 < Re < 2e5 (Re on the diameter and the velocity normal to the axis). Below Re = 1 it
// continues the fit (a log that slow in water is below 0.1 mm/s).
double cylinder_crossflow_drag_coefficient(double reynolds);

// Exponent chi of the voidage function eps^(-chi) of Di Felice, Int. J. Multiphase Flow 20
// (1994) 153-159: chi = 3.7 - 0.65 exp(-(1.5 - log10 Re)^2 / 2), Re = rho eps |u - v|
// d / mu on the superficial slip velocity. Re <= 0 gives the Stokes limit 3.7.
double di_felice_exponent(double reynolds);

// Lucy's quartic kernel in 3D (cosim/numerics/lucy_kernel.hpp; Lucy, Astron. J. 82 (1977)):
// W(r) = 105 / (16 pi R^3) (1 + 3 q) (1 - q)^3, q = r / R < 1, so that int W dV = 1; smooth with
// zero slope at 0 and R, so element volumes enter and leave the average gradually.
double voidage_kernel(double distance, double radius);

// Random close packing of equal spheres, phi = 0.64 (Scott & Kilgour, J. Phys. D 2 (1969)
// 863-866): the kernel estimate is floored at eps = 1 - 0.64, the densest state it stands for.
inline constexpr double kMinimumVoidage = 1.0 - 0.64;

// Local fluid volume fraction at each center: eps_i = 1 - sum_j V_j W(|x_i - x_j|; radius) over
// all elements j, i itself included (its own share of the averaging volume, as in the
// cell-average of unresolved CFD-DEM; a lone element sees 1 - V_i W(0), so the radius should be
// several diameters). Walls are not subtracted from the averaging volume. Floored at
// kMinimumVoidage. Deterministic summation order (cells of size radius, then index order).
std::vector<double> local_voidage(const std::vector<Eigen::Vector3d>& centers,
                                  const std::vector<double>& volumes, double radius);

}  // namespace cosim::dem
