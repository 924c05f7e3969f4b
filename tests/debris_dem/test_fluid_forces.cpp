// Closed forms of fluid_forces.hpp: submerged fractions against hydrostatics and independent
// quadrature, drag correlations, the Di Felice exponent and the voidage kernel on lattices.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>

#include "cosim/debris_dem/fluid_forces.hpp"

namespace cosim::dem {
namespace {

constexpr double kPi = std::numbers::pi;

TEST(SubmergedFraction, SphereCapAgainstDiskSlices) {
  const double r = 0.02;
  const double center = 0.3;
  for (const double depth : {0.0, 0.1, 0.5, 1.0, 1.3, 1.9, 2.0}) {
    const double surface = center - r + depth * r;
    // Independent: sum of horizontal disks pi (r^2 - z^2) below the surface (midpoint rule).
    const int n = 200000;
    double wet = 0.0;
    for (int i = 0; i < n; ++i) {
      const double z = -r + (i + 0.5) * 2 * r / n;
      if (center + z < surface) wet += kPi * (r * r - z * z) * 2 * r / n;
    }
    EXPECT_NEAR(sphere_submerged_fraction(center, r, surface), wet / (4.0 / 3.0 * kPi * r * r * r),
                1e-4)
        << depth;
  }
  EXPECT_NEAR(sphere_submerged_fraction(center, r, center), 0.5, 1e-15);
  EXPECT_EQ(sphere_submerged_fraction(center, r, -std::numeric_limits<double>::infinity()), 0.0);
  EXPECT_EQ(sphere_submerged_fraction(center, r, std::numeric_limits<double>::infinity()), 1.0);
}

// Segment share of a horizontal circle of diameter D wet to draft d: (theta - sin theta) /
// (2 pi) with theta = 2 acos(1 - 2 d / D) (settling_and_floating.md).
double segment_share(double draft_over_d) {
  const double theta = 2.0 * std::acos(1.0 - 2.0 * draft_over_d);
  return (theta - std::sin(theta)) / (2.0 * kPi);
}

TEST(SubmergedFraction, HorizontalLogIsTheCircularSegment) {
  const double d = 0.1;
  const Eigen::Vector3d center(0.4, -0.2, 1.0);
  for (const Eigen::Vector3d& axis : {Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(0.6, 0.8, 0)}) {
    for (const double draft : {0.0, 0.05, 0.25, 0.5, 0.746, 0.9, 1.0}) {
      const double surface = center.z() - 0.5 * d + draft * d;
      EXPECT_NEAR(cylinder_submerged_fraction(center, axis, 0.5 * d, 1.0, surface),
                  segment_share(draft), 1e-13)
          << draft;
    }
  }
  // Floating log of s.g. 0.8: solve share = 0.8 for the draft (reference: 0.746 D).
  double low = 0.0, high = 1.0;
  for (int i = 0; i < 100; ++i) {
    const double middle = 0.5 * (low + high);
    (segment_share(middle) < 0.8 ? low : high) = middle;
  }
  std::printf("s.g. 0.8 log: draft %.5f D (reference 0.746 D)\n", low);
  EXPECT_NEAR(low, 0.746, 5e-4);
  EXPECT_NEAR(cylinder_submerged_fraction(center, Eigen::Vector3d::UnitY(), 0.5 * d, 2.0,
                                          center.z() - 0.5 * d + low * d),
              0.8, 1e-12);
}

TEST(SubmergedFraction, UprightAndTiltedLogsAgainstClosedForms) {
  const double r = 0.05;
  const double length = 0.8;
  const Eigen::Vector3d center(0, 0, 0);
  // Upright: linear in the wet length.
  for (const double wet : {0.0, 0.1, 0.4, 0.8}) {
    EXPECT_NEAR(cylinder_submerged_fraction(center, Eigen::Vector3d::UnitZ(), r, length,
                                            -0.5 * length + wet),
                wet / length, 1e-14);
  }
  for (const double elevation_degrees : {5.0, 30.0, 60.0, 89.0}) {
    const double angle = elevation_degrees * kPi / 180;
    const Eigen::Vector3d axis(std::cos(angle), 0.3 * std::cos(angle), std::sin(angle));
    const Eigen::Vector3d a = axis.normalized();
    // Through the center: half, by point symmetry.
    EXPECT_NEAR(cylinder_submerged_fraction(center, a, r, length, 0.0), 0.5, 1e-13);
    // A plane that cuts only the side wall (clear of both end disks, whose z-extent is
    // +- r sin(tilt) about each end): the wedges above and below the axis point cancel, so the
    // wet volume is pi r^2 times the wet axis length.
    const double tilt = std::sqrt(1 - a.z() * a.z());
    const double end_z = 0.5 * length * a.z();
    for (const double s : {-0.6, -0.2, 0.3, 0.6}) {
      const double surface = s * (end_z - r * tilt);
      if (std::abs(surface) >= end_z - r * tilt) continue;
      const double wet_axis = surface / a.z() + 0.5 * length;
      EXPECT_NEAR(cylinder_submerged_fraction(center, a, r, length, surface), wet_axis / length,
                  1e-12)
          << elevation_degrees << " " << s;
    }
  }
  // Continuity through the near-horizontal branch.
  const double flat =
      cylinder_submerged_fraction(center, Eigen::Vector3d::UnitX(), r, length, 0.02);
  for (const double tiny : {1e-9, 1e-7, 1e-5}) {
    const Eigen::Vector3d a = Eigen::Vector3d(1, 0, tiny).normalized();
    EXPECT_NEAR(cylinder_submerged_fraction(center, a, r, length, 0.02), flat, 1e-9) << tiny;
  }
  EXPECT_EQ(cylinder_submerged_fraction(center, Eigen::Vector3d::UnitX(), r, length,
                                        -std::numeric_limits<double>::infinity()),
            0.0);
}

TEST(SubmergedFraction, TiltedLogCutThroughAnEndAgainstQuadrature) {
  // The plane cuts the lower end disk: no symmetry shortcut; compare with cylindrical-coordinate
  // midpoint quadrature (error ~ 1 / number of cells across the cut).
  const double r = 0.05;
  const double length = 0.4;
  const Eigen::Vector3d center(0.1, 0.2, 0.3);
  const Eigen::Vector3d a = Eigen::Vector3d(0.5, -0.4, 0.3).normalized();
  const Eigen::Vector3d u = a.unitOrthogonal();
  const Eigen::Vector3d v = a.cross(u);
  const double lowest =
      center.z() - 0.5 * length * std::abs(a.z()) - r * std::sqrt(1 - a.z() * a.z());
  for (const double above_lowest : {0.01, 0.04, 0.12}) {
    const double surface = lowest + above_lowest;
    const int nt = 200, nr = 100, nphi = 200;
    double wet = 0.0, total = 0.0;
    for (int i = 0; i < nt; ++i) {
      const double t = -0.5 * length + (i + 0.5) * length / nt;
      for (int j = 0; j < nr; ++j) {
        const double rho = (j + 0.5) * r / nr;
        for (int k = 0; k < nphi; ++k) {
          const double phi = (k + 0.5) * 2 * kPi / nphi;
          const double z =
              center.z() + t * a.z() + rho * (std::cos(phi) * u.z() + std::sin(phi) * v.z());
          total += rho;
          if (z < surface) wet += rho;
        }
      }
    }
    EXPECT_NEAR(cylinder_submerged_fraction(center, a, r, length, surface), wet / total, 2e-3)
        << above_lowest;
  }
}

TEST(DragCorrelations, SchillerNaumannCrossflowAndDiFelice) {
  EXPECT_NEAR(schiller_naumann_drag_coefficient(1.0), 24.0 * 1.15, 1e-12);
  EXPECT_NEAR(schiller_naumann_drag_coefficient(100.0), 0.24 * (1 + 0.15 * std::pow(100.0, 0.687)),
              1e-12);
  EXPECT_DOUBLE_EQ(schiller_naumann_drag_coefficient(5000.0), 0.44);
  // Stokes limit: C_D Re -> 24.
  EXPECT_NEAR(schiller_naumann_drag_coefficient(1e-8) * 1e-8, 24.0, 1e-4);
  EXPECT_NEAR(cylinder_crossflow_drag_coefficient(1000.0), 1.1, 1e-12);
  EXPECT_NEAR(cylinder_crossflow_drag_coefficient(1.0), 11.0, 1e-12);
  // chi dips to 3.7 - 0.65 at log10 Re = 1.5 and returns to 3.7 at both ends.
  EXPECT_NEAR(di_felice_exponent(std::pow(10.0, 1.5)), 3.05, 1e-12);
  EXPECT_NEAR(di_felice_exponent(1e-6), 3.7, 1e-6);
  EXPECT_NEAR(di_felice_exponent(1e8), 3.7, 1e-6);
  EXPECT_DOUBLE_EQ(di_felice_exponent(0.0), 3.7);
}

TEST(Voidage, KernelIsNormalisedAndLatticeAverageIsTheSolidFraction) {
  const double radius = 0.07;
  const int n = 100000;
  double integral = 0.0;
  for (int i = 0; i < n; ++i) {
    const double r = (i + 0.5) * radius / n;
    integral += 4 * kPi * r * r * voidage_kernel(r, radius) * radius / n;
  }
  EXPECT_NEAR(integral, 1.0, 1e-9);
  EXPECT_EQ(voidage_kernel(radius, radius), 0.0);

  // Spheres of diameter d on a cubic lattice of spacing s: solid fraction pi d^3 / (6 s^3).
  const double d = 0.015;
  const double s = 1.5 * d;
  const double volume = kPi * d * d * d / 6;
  const double phi = volume / (s * s * s);
  std::vector<Eigen::Vector3d> centers;
  for (int i = -4; i <= 4; ++i)
    for (int j = -4; j <= 4; ++j)
      for (int k = -4; k <= 4; ++k) centers.emplace_back(Eigen::Vector3d(i, j, k) * s);
  const std::vector<double> volumes(centers.size(), volume);
  const std::size_t middle = centers.size() / 2;
  for (const double reach : {2.5, 3.0, 4.0}) {
    const auto eps = local_voidage(centers, volumes, reach * s);
    std::printf("lattice phi %.4f, kernel radius %.1f s: 1 - eps %.4f\n", phi, reach,
                1 - eps[middle]);
    // Lattice sums of this kernel differ from its integral by < 0.3 % for R >= 2.5 s.
    EXPECT_NEAR(1 - eps[middle], phi, 3e-3 * phi) << reach;
    // A corner element sees an eighth of the kernel plus its weight on the three boundary
    // planes through itself: well under half the solid.
    EXPECT_LT(1 - eps[0], 0.5 * phi);
  }
  // A lone element sees only its own share V W(0).
  const auto lone = local_voidage({Eigen::Vector3d::Zero()}, {volume}, 3 * d);
  EXPECT_NEAR(lone[0], 1 - volume * voidage_kernel(0.0, 3 * d), 1e-15);
  // Piled on one point the estimate stops at random close packing.
  const std::vector<Eigen::Vector3d> pile(20, Eigen::Vector3d::Zero());
  EXPECT_DOUBLE_EQ(local_voidage(pile, std::vector<double>(20, volume), 2 * d)[0], kMinimumVoidage);
  EXPECT_THROW(local_voidage(centers, volumes, 0.0), std::invalid_argument);
}

}  // namespace
}  // namespace cosim::dem
