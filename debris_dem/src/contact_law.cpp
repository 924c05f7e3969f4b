#include "cosim/debris_dem/contact_law.hpp"

#include <cmath>

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

void apply_contact_law(ContactPair& pair, const ContactGeometry& geometry,
                       const Eigen::Vector3d& relative_velocity, double dt, bool clip) {
  const Eigen::Vector3d& n = geometry.normal;
  pair.touching = true;
  pair.overlap = geometry.overlap;
  // Normal: P_n = K_n delta_n plus the dashpot; approach (v.n < 0) compresses.
  const double normal_velocity = relative_velocity.dot(n);
  double normal_force =
      pair.normal_stiffness * geometry.overlap - pair.normal_damping * normal_velocity;
  if (clip && normal_force < 0.0) normal_force = 0.0;  // fig. 3a: no tension

  // Tangential: rotate the stored shear onto the current tangent plane (the local frame of the
  // pair spring turns with the contact, eq. 10-12), keep its length, add this step's increment.
  const Eigen::Vector3d tangential_velocity = relative_velocity - normal_velocity * n;
  Eigen::Vector3d spring = pair.tangential_spring;
  const double old_length = spring.norm();
  spring -= spring.dot(n) * n;
  const double new_length = spring.norm();
  if (new_length > 0.0) spring *= old_length / new_length;
  spring += tangential_velocity * dt;  // eq. (11): S(t) = S(t - dt) + k dq
  Eigen::Vector3d tangential_force =
      -pair.tangential_stiffness * spring - pair.tangential_damping * tangential_velocity;
  // Mohr-Coulomb, cohesion 0 (fig. 3b): |P_s| <= P_n tan(phi). While sliding the spring holds
  // exactly the limit force, so sliding stops smoothly when the load drops.
  const double limit = pair.friction * std::max(normal_force, 0.0);
  const double magnitude = tangential_force.norm();
  if (magnitude > limit) {
    tangential_force *= magnitude > 0.0 ? limit / magnitude : 0.0;
    spring = pair.tangential_stiffness > 0.0
                 ? Eigen::Vector3d(-tangential_force / pair.tangential_stiffness)
                 : Eigen::Vector3d::Zero();
  }
  pair.tangential_spring = spring;
  pair.force_on_a = normal_force * n + tangential_force;
}

double contact_elastic_energy(const ContactPair& pair) {
  if (!pair.touching) return 0.0;
  return 0.5 * pair.normal_stiffness * pair.overlap * pair.overlap +
         0.5 * pair.tangential_stiffness * pair.tangential_spring.squaredNorm();
}

}  // namespace cosim::dem
