#include "beam_elements.hpp"

#include <Eigen/Geometry>
#include <cmath>

namespace cosim::vegetation {
namespace {

Eigen::Matrix3d cross_matrix(const Eigen::Vector3d& a) {
  Eigen::Matrix3d m;
  m << 0, -a.z(), a.y(), a.z(), 0, -a.x(), -a.y(), a.x(), 0;
  return m;
}

}  // namespace

AxialLink axial_link(const Eigen::Vector3d& xa, const Eigen::Vector3d& xb,
                     const Eigen::Vector3d& va, const Eigen::Vector3d& vb, double spring,
                     double damper, double rest_length, bool with_matrices) {
  AxialLink out;
  const Eigen::Vector3d r = xb - xa;
  const double length = r.norm();
  const Eigen::Vector3d e = r / length;
  const double stretch = length - rest_length;
  const double stretch_rate = (vb - va).dot(e);
  out.force_on_b = -(spring * stretch + damper * stretch_rate) * e;
  out.energy = 0.5 * spring * stretch * stretch;
  if (!with_matrices) return out;
  const Eigen::Matrix3d along = e * e.transpose();
  // Transverse term (1 - l0/L): rotating a stretched spring needs force (geometric stiffness).
  out.stiffness =
      spring * (along + (1.0 - rest_length / length) * (Eigen::Matrix3d::Identity() - along));
  out.damping = damper * along;
  return out;
}

void bending_joint(const Eigen::Vector3d x[3], const Eigen::Vector3d v[3], double spring,
                   double damper, bool with_matrices, BendingJoint& out) {
  const Eigen::Vector3d a = x[1] - x[0], b = x[2] - x[1];
  const double la = a.norm(), lb = b.norm();
  const Eigen::Vector3d ah = a / la, bh = b / lb;
  const double c = ah.dot(bh);
  const double s = ah.cross(bh).norm();
  const double phi = std::atan2(s, c);
  // E = spring * F(c) with F = acos(c)^2 / 2; h1 = -F'(c) = phi / sin(phi),
  // h2 = F''(c) = (sin(phi) - phi cos(phi)) / sin(phi)^3, both smooth at phi = 0.
  double h1, h2;
  if (phi < 1e-4) {
    h1 = 1.0 + phi * phi / 6.0;
    h2 = 1.0 / 3.0 + 2.0 * phi * phi / 15.0;
  } else {
    h1 = phi / s;
    h2 = (s - phi * c) / (s * s * s);
  }
  const Eigen::Vector3d dc_da = (bh - c * ah) / la;  // gradient of cos(phi) by link a
  const Eigen::Vector3d dc_db = (ah - c * bh) / lb;
  out.energy = 0.5 * spring * phi * phi;
  out.force[0] = -spring * h1 * dc_da;
  out.force[2] = spring * h1 * dc_db;
  out.force[1] = -out.force[0] - out.force[2];

  // Dashpot on the relative angular velocity of the links, omega = l x dl/dt / |l|^2:
  // omega = T_0 v_0 + T_1 v_1 + T_2 v_2 with T_0 = [a]x / la^2, T_2 = [b]x / lb^2 and
  // T_1 = -(T_0 + T_2), and the force on node n is -damper T_n^T omega ([l]x^T w = w x l).
  const double la2 = la * la, lb2 = lb * lb;
  if (damper > 0) {
    const Eigen::Vector3d omega = a.cross(v[0] - v[1]) / la2 + b.cross(v[2] - v[1]) / lb2;
    const Eigen::Vector3d on_a = damper * a.cross(omega) / la2;
    const Eigen::Vector3d on_b = damper * b.cross(omega) / lb2;
    out.force[0] += on_a;
    out.force[1] -= on_a + on_b;
    out.force[2] += on_b;
  }
  if (!with_matrices) return;
  const Eigen::Matrix3d rate_a = cross_matrix(a) / la2;
  const Eigen::Matrix3d rate_b = cross_matrix(b) / lb2;
  const Eigen::Matrix3d to_omega[3] = {rate_a, -(rate_a + rate_b), rate_b};

  const Eigen::Matrix3d identity = Eigen::Matrix3d::Identity();
  const Eigen::Matrix3d pa = identity - ah * ah.transpose();
  const Eigen::Matrix3d pb = identity - bh * bh.transpose();
  const Eigen::Matrix3d d2c_aa =
      -(ah * dc_da.transpose() + dc_da * ah.transpose() + c * pa / la) / la;
  const Eigen::Matrix3d d2c_bb =
      -(bh * dc_db.transpose() + dc_db * bh.transpose() + c * pb / lb) / lb;
  const Eigen::Matrix3d d2c_ab = pa * pb / (la * lb);
  const Eigen::Matrix3d h_aa = spring * (h2 * dc_da * dc_da.transpose() - h1 * d2c_aa);
  const Eigen::Matrix3d h_bb = spring * (h2 * dc_db * dc_db.transpose() - h1 * d2c_bb);
  const Eigen::Matrix3d h_ab = spring * (h2 * dc_da * dc_db.transpose() - h1 * d2c_ab);
  const Eigen::Matrix3d h_ba = h_ab.transpose();
  // Chain rule from (a, b) to nodes: a = x1 - x0, b = x2 - x1, so node 0 sees -a, node 1 a - b,
  // node 2 b. Both matrices are symmetric: the blocks below the diagonal are taken as the
  // transposes of those above, so those pairs match to the bit (the diagonal blocks are
  // symmetric to round-off: h2 dc dc^T rounds its two halves differently).
  out.stiffness[0][0] = h_aa;
  out.stiffness[0][1] = h_ab - h_aa;
  out.stiffness[0][2] = -h_ab;
  out.stiffness[1][1] = ((h_aa - h_ab) - h_ba) + h_bb;
  out.stiffness[1][2] = h_ab - h_bb;
  out.stiffness[2][2] = h_bb;
  for (int n = 0; n < 3; ++n) {
    for (int m = n; m < 3; ++m) out.damping[n][m] = damper * to_omega[n].transpose() * to_omega[m];
  }
  for (int n = 1; n < 3; ++n) {
    for (int m = 0; m < n; ++m) {
      out.stiffness[n][m] = out.stiffness[m][n].transpose();
      out.damping[n][m] = out.damping[m][n].transpose();
    }
  }
}

NodeDrag node_drag(const Eigen::Vector3d& tangent, const Eigen::Vector3d& ambient,
                   const Eigen::Vector3d& velocity, double factor, bool with_tangent_stiffness,
                   bool with_matrices) {
  NodeDrag out;
  const Eigen::Vector3d relative = ambient - velocity;
  const double along = relative.dot(tangent);
  const Eigen::Vector3d normal = relative - along * tangent;
  const double speed = normal.norm();
  out.force = factor * speed * normal;
  out.tangent_stiffness.setZero();
  if (!with_matrices && !with_tangent_stiffness) return out;
  if (speed > 0) {
    const Eigen::Vector3d direction = normal / speed;
    const Eigen::Matrix3d across = Eigen::Matrix3d::Identity() - tangent * tangent.transpose();
    out.damping = factor * speed * (across + direction * direction.transpose());
    if (with_tangent_stiffness) {
      // u_n = r - (r.t) t: d u_n / d t = -((r.t) I + t r^T), d F / d u_n = f |u_n| (I + n n^T).
      const Eigen::Matrix3d by_normal =
          factor * speed * (Eigen::Matrix3d::Identity() + direction * direction.transpose());
      out.tangent_stiffness =
          by_normal * (along * Eigen::Matrix3d::Identity() + tangent * relative.transpose());
    }
  } else {
    out.damping.setZero();
  }
  return out;
}

}  // namespace cosim::vegetation
