#include "attitude.hpp"

#include <cmath>

namespace cosim::dem {
namespace {

// The unit quaternion of a turn by omega dt (angle = |omega| dt > 0, rad):
// (cos(angle / 2), sin(angle / 2) omega / |omega|). sin(h) / h and cos(h) of the half angle h by
// their series below h^2 = 1e-6 (the first omitted terms, h^6 / 5040 and h^6 / 720, are under
// 1.4e-21, far below round-off; a DEM step turns an element by 1e-5 to 1e-3 rad), so the usual
// step needs no sine, cosine, square root or division.
Eigen::Quaterniond turn(const Eigen::Vector3d& omega, double angle, double dt) {
  const double half = 0.5 * angle, h2 = half * half;
  double cosine = 0.0, sine_over_half = 0.0;
  if (h2 < 1e-6) {
    cosine = 1.0 - 0.5 * h2 * (1.0 - h2 * (1.0 / 12.0));
    sine_over_half = 1.0 - h2 * (1.0 / 6.0) * (1.0 - h2 * (1.0 / 20.0));
  } else {
    cosine = std::cos(half);
    sine_over_half = std::sin(half) / half;
  }
  // sin(h) omega / |omega| = (sin(h) / h) (dt / 2) omega, since h = |omega| dt / 2.
  const Eigen::Vector3d axis_part = omega * (0.5 * dt * sine_over_half);
  return {cosine, axis_part.x(), axis_part.y(), axis_part.z()};
}

// A product of unit quaternions is unit to round-off: one Newton step of 1 / sqrt(n) about 1
// (error of order (n - 1)^2) keeps it so without a square root; a quaternion farther from unit
// length is normalised in full.
Eigen::Quaterniond renormalised(Eigen::Quaterniond q) {
  const double n2 = q.squaredNorm();
  if (std::abs(n2 - 1.0) < 1e-8) {
    q.coeffs() *= 1.5 - 0.5 * n2;
  } else {
    q.normalize();
  }
  return q;
}

}  // namespace

// The torque-free turn of an axisymmetric body (a log) over dt with its angular momentum L held
// fixed, exactly: for principal moments I_t (transverse) and I_a (about the axis a), the body
// turns about L at |L| / I_t while it spins about its own axis at s = (L . a)(1 / I_a - 1 / I_t),
// and the two turns compose as R(t) = exp(t [L / I_t]) R0 exp(t s [e_z]) (the free symmetric top;
// Dullweber, Leimkuhler & McLachlan 1997, J. Chem. Phys. 107, 5840, use this split for rigid
// bodies). Both turns keep L . a, so a log spinning fast end over end stays so; a single turn
// by omega dt does not, and with I_t / I_a = 67 (a 10 x 100 mm log) at 2000 rad/s and dt = 1e-5 s
// the error grew until the log spun about its own axis at 67 times the energy
// (DemWorld.LogSpinningEndOverEndTurnsItsAxisUniformly).
Eigen::Quaterniond free_top_turn(const Eigen::Quaterniond& q, const Eigen::Vector3d& momentum,
                                 const Eigen::Vector3d& axis, const Eigen::Vector3d& inertia,
                                 double dt) {
  const Eigen::Vector3d precession = momentum / inertia.x();  // rad/s
  const double spin = momentum.dot(axis) * (1.0 / inertia.z() - 1.0 / inertia.x());
  Eigen::Quaterniond result = q;
  const double precession_angle = precession.norm() * dt;
  if (precession_angle > 0.0) result = turn(precession, precession_angle, dt) * result;
  const double spin_angle = std::abs(spin) * dt;
  if (spin_angle > 0.0) result = result * turn(Eigen::Vector3d(0, 0, spin), spin_angle, dt);
  return renormalised(result);
}

}  // namespace cosim::dem
