#include "cosim/debris_dem/contact_law.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

namespace cosim::dem {

PairConstants pair_constants(double kn_a, double kn_b, double kt_a, double kt_b, double zeta_a,
                             double zeta_b, double mu_a, double mu_b, double mass_a,
                             double mass_b) {
  // Means of the two materials: identical materials reproduce the table 3 constants exactly.
  PairConstants c{};
  c.normal_stiffness = 0.5 * (kn_a + kn_b);
  c.tangential_stiffness = 0.5 * (kt_a + kt_b);
  c.friction = 0.5 * (mu_a + mu_b);
  const double zeta = 0.5 * (zeta_a + zeta_b);
  // A fixed element has infinite mass (mass <= 0 here): the moving one carries the motion.
  double effective_mass = 0.0;
  if (mass_a > 0.0 && mass_b > 0.0) {
    effective_mass = mass_a * mass_b / (mass_a + mass_b);
  } else {
    effective_mass = mass_a > 0.0 ? mass_a : mass_b;
  }
  c.normal_damping = 2.0 * zeta * std::sqrt(effective_mass * c.normal_stiffness);
  c.tangential_damping = 2.0 * zeta * std::sqrt(effective_mass * c.tangential_stiffness);
  return c;
}

double clipped_restitution(double zeta) {
  if (!(zeta >= 0.0)) throw std::invalid_argument("clipped_restitution: zeta must be >= 0");
  // Time in units of 1/omega_0, omega_0 = sqrt(k / m_eff); x(0) = 0, x'(0) = v. The force
  // k x + c x' = -m x'' first vanishes at t1 and the bodies leave with x'(t1) = -e v.
  constexpr double kCritical = 1e-7;  // band around zeta = 1 where both forms lose digits
  if (zeta < 1.0 - kCritical) {
    // Underdamped: x'' = 0 at omega_d t1 = atan2(2 zeta w, 2 zeta^2 - 1),
    // w = sqrt(1 - zeta^2), where |x'| = v exp(-zeta t1) exactly.
    const double w = std::sqrt(1.0 - zeta * zeta);
    const double phase = std::atan2(2.0 * zeta * w, 2.0 * zeta * zeta - 1.0);
    return std::exp(-zeta * phase / w);
  }
  if (zeta <= 1.0 + kCritical) return std::exp(-2.0);  // critical damping
  // Overdamped: x ~ exp(-r1 t) - exp(-r2 t), r = zeta -+ sqrt(zeta^2 - 1); x'' = 0 at
  // t1 = 2 ln(r2 / r1) / (r2 - r1), where x' = -v (r1 / r2) exp(-r1 t1).
  const double q = std::sqrt(zeta * zeta - 1.0);
  const double ratio = (zeta - q) / (zeta + q);
  return std::pow(ratio, 1.0 + 2.0 * (zeta - q) / (2.0 * q));
}

double damping_ratio_for_restitution(double e, bool clipped) {
  if (!(e > 0.0 && e < 1.0)) {
    throw std::invalid_argument("damping_ratio_for_restitution: e must lie in (0, 1)");
  }
  const double log_e = std::log(e);
  // Unclipped: inverse of e = exp(-pi zeta / sqrt(1 - zeta^2)) (references/dem_contact.md).
  const double free_zeta = -log_e / std::sqrt(std::numbers::pi * std::numbers::pi + log_e * log_e);
  if (!clipped) return free_zeta;
  // Clipped: the clipped law ends the contact early and so dissipates less for the same zeta;
  // clipped_restitution falls monotonically from 1 (zeta = 0) to 0 (zeta -> infinity). Bracket
  // from the unclipped zeta upwards, then bisect to round-off (once per material).
  double low = 0.0;
  double high = std::max(free_zeta, 1e-3);
  while (clipped_restitution(high) > e) {
    low = high;
    high *= 2.0;
    if (high > 1e8) throw std::invalid_argument("damping_ratio_for_restitution: e too small");
  }
  for (int iteration = 0; iteration < 200 && high - low > 1e-15 * high; ++iteration) {
    const double middle = 0.5 * (low + high);
    (clipped_restitution(middle) > e ? low : high) = middle;
  }
  return 0.5 * (low + high);
}

double contact_elastic_energy(const ContactPair& pair) {
  if (!pair.touching) return 0.0;
  return 0.5 * pair.normal_stiffness * pair.overlap * pair.overlap +
         0.5 * pair.tangential_stiffness * pair.tangential_spring.squaredNorm();
}

}  // namespace cosim::dem
