// Spring-dashpot contact law of seed 004 section 2.3: a normal spring that resists compression
// only (fig. 3a) and a tangential spring limited by Mohr-Coulomb (fig. 3b), each with a parallel
// dashpot; the tangential spring is incremental (eq. 11) and kept per contact pair.
#pragma once

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdint>

#include "cosim/debris_dem/contact_geometry.hpp"

namespace cosim::dem {

enum class PairKind : std::uint8_t {
  kSphereSphere,
  kSphereCylinder,
  kCylinderCylinder,
  kSphereTriangle,
  kCylinderTriangle,
};

struct ContactPair {
  int a = -1;  // sphere before cylinder before triangle; a < b for equal kinds
  int b = -1;
  PairKind kind = PairKind::kSphereSphere;
  double normal_stiffness = 0.0;
  double tangential_stiffness = 0.0;
  double normal_damping = 0.0;
  double tangential_damping = 0.0;
  double friction = 0.0;
  Eigen::Vector3d tangential_spring = Eigen::Vector3d::Zero();  // shear displacement, world
  bool touching = false;
  // Results of the last evaluation.
  Eigen::Vector3d force_on_a = Eigen::Vector3d::Zero();
  Eigen::Vector3d lever_a = Eigen::Vector3d::Zero();  // contact point minus A's center
  Eigen::Vector3d lever_b = Eigen::Vector3d::Zero();  // contact point minus B's center
  double overlap = 0.0;
  double overlap_ratio = 0.0;  // overlap / smaller radius of the pair
};

// Spring and dashpot constants of a pair from the two materials' values and masses:
// c = 2 zeta sqrt(m_eff k) for both directions (seed 004 gives c_n, c_s per particle size).
struct PairConstants {
  double normal_stiffness;
  double tangential_stiffness;
  double normal_damping;
  double tangential_damping;
  double friction;
};
PairConstants pair_constants(double kn_a, double kn_b, double kt_a, double kt_b, double zeta_a,
                             double zeta_b, double mu_a, double mu_b, double mass_a, double mass_b);

// Restitution of the linear spring-dashpot with damping ratio zeta when the total normal force
// is clipped at zero (no tension): the contact ends as soon as k x + c x' = 0, before the overlap
// closes. Closed form of Schwager & Poeschel, Granular Matter 9 (2007) 465-469;
// e.g. zeta = 0.2 gives 0.572 where the unclipped law gives 0.527.
double clipped_restitution(double zeta);

// Damping ratio that gives restitution e (0 < e < 1) under either normal law: the inverse of
// e = exp(-pi zeta / sqrt(1 - zeta^2)) when the dashpot may pull, the numerical inverse of
// clipped_restitution() otherwise (reaches any e > 0: the clipped law's e falls below exp(-2)
// only for an overdamped dashpot, zeta > 1).
double damping_ratio_for_restitution(double e, bool clipped);

// The law on a pair's constants and tangential spring (m, world frame, advanced here): the force
// on A (N) for a touching geometry with the given overlap (m) and unit normal n from B to A, and
// the relative velocity v_A - v_B (m/s) at the contact point over a step of dt (s).
// clip: total normal force >= 0.
// The Coulomb limit is friction times the normal force the contact transmits over an impact:
// clipped, the total (spring + dashpot, >= 0); unclipped, the spring part k delta (Cundall &
// Strack, Geotechnique 29 (1979) 47-65, who check the elastic forces against Coulomb before
// adding the dashpots). The dashpot's impulse c [delta] vanishes over a whole unclipped contact,
// so either way the friction impulse of a sliding impact is mu times its normal impulse, as in
// the rigid-body closed forms (references/dem_contact.md), and friction never pushes.
// Forced inline: the contact loop calls it for every touching pair of every step, on its compact
// pair state (no ContactPair is assembled there); GCC 12 otherwise calls it and spills the pair's
// vectors around the call.
[[gnu::always_inline]] inline Eigen::Vector3d contact_force(
    const PairConstants& c, double overlap, const Eigen::Vector3d& n,
    const Eigen::Vector3d& relative_velocity, double dt, bool clip,
    Eigen::Vector3d& tangential_spring) {
  // Normal: P_n = K_n delta_n plus the dashpot; approach (v.n < 0) compresses.
  const double normal_velocity = relative_velocity.dot(n);
  double normal_force = c.normal_stiffness * overlap - c.normal_damping * normal_velocity;
  if (clip && normal_force < 0.0) normal_force = 0.0;  // fig. 3a: no tension

  // Tangential: rotate the stored shear onto the current tangent plane (the local frame of the
  // pair spring turns with the contact, eq. 10-12), keep its length, add this step's increment.
  const Eigen::Vector3d tangential_velocity = relative_velocity - normal_velocity * n;
  Eigen::Vector3d spring = tangential_spring;
  const double old_length_squared = spring.squaredNorm();
  spring -= spring.dot(n) * n;
  const double new_length_squared = spring.squaredNorm();
  if (new_length_squared > 0.0) spring *= std::sqrt(old_length_squared / new_length_squared);
  spring += tangential_velocity * dt;  // eq. (11): S(t) = S(t - dt) + k dq
  Eigen::Vector3d tangential_force =
      -c.tangential_stiffness * spring - c.tangential_damping * tangential_velocity;
  // Mohr-Coulomb, cohesion 0 (fig. 3b): |P_s| <= P_n tan(phi), P_n the transmitted normal force
  // (see above: clipped total, or the spring part when the dashpot may pull). While sliding the
  // spring holds exactly the limit force, so sliding stops smoothly when the load drops.
  const double coulomb_load = clip ? normal_force : c.normal_stiffness * overlap;
  const double limit = c.friction * std::max(coulomb_load, 0.0);
  // Compared squared: a sticking contact (most of a packed bed's) needs no square root.
  const double magnitude_squared = tangential_force.squaredNorm();
  if (magnitude_squared > limit * limit) {
    const double magnitude = std::sqrt(magnitude_squared);
    tangential_force *= magnitude > 0.0 ? limit / magnitude : 0.0;
    spring = c.tangential_stiffness > 0.0
                 ? Eigen::Vector3d(-tangential_force / c.tangential_stiffness)
                 : Eigen::Vector3d::Zero();
  }
  tangential_spring = spring;
  return normal_force * n + tangential_force;
}

// contact_force() on a ContactPair: evaluates the force on A for a touching geometry and
// relative velocity v_A - v_B at the contact point; updates the tangential spring.
inline void apply_contact_law(ContactPair& pair, const ContactGeometry& geometry,
                              const Eigen::Vector3d& relative_velocity, double dt, bool clip) {
  pair.touching = true;
  pair.overlap = geometry.overlap;
  const PairConstants c{pair.normal_stiffness, pair.tangential_stiffness, pair.normal_damping,
                        pair.tangential_damping, pair.friction};
  pair.force_on_a = contact_force(c, geometry.overlap, geometry.normal, relative_velocity, dt, clip,
                                  pair.tangential_spring);
}

// Energy held by the pair's springs (normal 0.5 k delta^2, tangential 0.5 k_s |xi|^2).
double contact_elastic_energy(const ContactPair& pair);

}  // namespace cosim::dem
