#include "cosim/debris_dem/fluid_forces.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <utility>

#include "cosim/numerics/lucy_kernel.hpp"

namespace cosim::dem {
namespace {

constexpr double kPi = std::numbers::pi;

// Area (in units of r^2) of a unit disk below a chord at signed height x above its center:
// a(x) = pi - acos(x) + x sqrt(1 - x^2) on [-1, 1], 0 below, pi above (da/dx = chord length
// 2 sqrt(1 - x^2)).
double segment_area(double x) {
  if (x <= -1.0) return 0.0;
  if (x >= 1.0) return kPi;
  return kPi - std::acos(x) + x * std::sqrt(1.0 - x * x);
}

// Antiderivative of segment_area with value 0 at x = -1:
// P(x) = pi x - x acos(x) + sqrt(1 - x^2) - (1 - x^2)^(3/2) / 3 on [-1, 1] (P(1) = pi), and
// pi x above 1 where the whole disk is submerged.
double segment_area_integral(double x) {
  if (x <= -1.0) return 0.0;
  if (x >= 1.0) return kPi * x;
  const double w = 1.0 - x * x;
  const double root = std::sqrt(w);
  return kPi * x - x * std::acos(x) + root - w * root / 3.0;
}

}  // namespace

double sphere_submerged_fraction(double center_z, double radius, double surface_z) {
  if (std::isnan(surface_z)) throw std::invalid_argument("sphere_submerged_fraction: NaN surface");
  const double h = surface_z - (center_z - radius);
  if (h <= 0.0) return 0.0;
  if (h >= 2.0 * radius) return 1.0;
  // Cap volume pi h^2 (3 r - h) / 3 over the sphere's 4/3 pi r^3.
  return std::min(1.0, h * h * (3.0 * radius - h) / (4.0 * radius * radius * radius));
}

double cylinder_submerged_fraction(const Eigen::Vector3d& center, const Eigen::Vector3d& axis_unit,
                                   double radius, double length, double surface_z) {
  if (std::isnan(surface_z)) {
    throw std::invalid_argument("cylinder_submerged_fraction: NaN surface");
  }
  if (std::isinf(surface_z)) return surface_z > 0.0 ? 1.0 : 0.0;
  const double vertical = axis_unit.z();  // cosine of the axis angle from the vertical
  const double tilt = std::sqrt(std::max(0.0, 1.0 - vertical * vertical));  // its sine
  const double half = 0.5 * length;
  if (tilt < 1e-12) {
    // Upright: every cross-section is a horizontal disk, wholly wet or dry; the error of this
    // limit is the disks' height r * tilt < 1e-12 r.
    const double bottom = center.z() - half * std::abs(vertical);
    return std::clamp((surface_z - bottom) / length, 0.0, 1.0);
  }
  // The slice at axial coordinate t is a disk whose water line lies at the in-plane height
  // h(t) = (surface_z - z(t)) / tilt above its center, z(t) = center_z + t vertical; its wet
  // area is r^2 a(h / r). h is linear in t, so the volume is r^2 L times the mean of a over
  // [x1, x2], x = h / r at the two ends, which the antiderivative gives exactly.
  const double x1 = (surface_z - (center.z() - half * vertical)) / (radius * tilt);
  const double x2 = (surface_z - (center.z() + half * vertical)) / (radius * tilt);
  // Nearly horizontal: the difference of P would cancel; the midpoint value is then exact to
  // O((x2 - x1)^2) < 1e-12.
  if (std::abs(x2 - x1) < 1e-6) return segment_area(0.5 * (x1 + x2)) / kPi;
  const double mean_area =
      (segment_area_integral(x2) - segment_area_integral(x1)) / (x2 - x1);  // in units of r^2
  return std::clamp(mean_area / kPi, 0.0, 1.0);
}

double schiller_naumann_drag_coefficient(double reynolds) {
  if (!(reynolds > 0.0)) return std::numeric_limits<double>::infinity();
  if (reynolds >= 1000.0) return 0.44;
  return 24.0 / reynolds * (1.0 + 0.15 * std::pow(reynolds, 0.687));
}

double cylinder_crossflow_drag_coefficient(double reynolds) {
  if (!(reynolds > 0.0)) return std::numeric_limits<double>::infinity();
  return 1.0 + 10.0 * std::pow(reynolds, -2.0 / 3.0);
}

double di_felice_exponent(double reynolds) {
  if (!(reynolds > 0.0)) return 3.7;
  const double offset = 1.5 - std::log10(reynolds);
  return 3.7 - 0.65 * std::exp(-0.5 * offset * offset);
}

double voidage_kernel(double distance, double radius) {
  return numerics::lucy_kernel(distance, radius, 3);
}

std::vector<double> local_voidage(const std::vector<Eigen::Vector3d>& centers,
                                  const std::vector<double>& volumes, double radius) {
  if (!(radius > 0.0)) throw std::invalid_argument("local_voidage: radius must be positive");
  if (volumes.size() != centers.size()) {
    throw std::invalid_argument("local_voidage: one volume per center");
  }
  const std::size_t n = centers.size();
  // Cells of edge `radius`: the kernel's support reaches only the 27 cells around a center.
  std::vector<Eigen::Vector3i> cell(n);
  const auto key = [](const Eigen::Vector3i& c) {
    constexpr std::int64_t kOffset = 1 << 20;
    return ((c.x() + kOffset) << 42) | ((c.y() + kOffset) << 21) | (c.z() + kOffset);
  };
  std::vector<std::pair<std::int64_t, int>> sorted(n);
  for (std::size_t i = 0; i < n; ++i) {
    cell[i] = (centers[i] / radius).array().floor().cast<int>().matrix();
    sorted[i] = {key(cell[i]), static_cast<int>(i)};
  }
  std::sort(sorted.begin(), sorted.end());
  std::vector<double> voidage(n, 1.0);
  for (std::size_t i = 0; i < n; ++i) {
    double solid = 0.0;
    for (int dx = -1; dx <= 1; ++dx) {
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dz = -1; dz <= 1; ++dz) {
          const std::int64_t k = key(cell[i] + Eigen::Vector3i(dx, dy, dz));
          auto it = std::lower_bound(sorted.begin(), sorted.end(), std::pair(k, -1));
          for (; it != sorted.end() && it->first == k; ++it) {
            const int j = it->second;
            solid += volumes[j] * voidage_kernel((centers[i] - centers[j]).norm(), radius);
          }
        }
      }
    }
    voidage[i] = std::max(kMinimumVoidage, 1.0 - solid);
  }
  return voidage;
}

}  // namespace cosim::dem
