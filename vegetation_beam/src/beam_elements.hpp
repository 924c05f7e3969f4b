// Force, stiffness and damping kernels of the beam elements. Stiffness is minus the derivative
// of the force by position, damping minus the derivative by velocity; together they give the
// Newton Jacobian of the Newmark step.
#pragma once

#include <Eigen/Core>

namespace cosim::vegetation {

// Axial spring-dashpot between nodes a and b (seed eq. 9, 12, 14).
struct AxialLink {
  Eigen::Vector3d force_on_b;  // force on a is the opposite
  Eigen::Matrix3d stiffness;   // block (b,b) and (a,a); off-diagonal blocks are its negative
  Eigen::Matrix3d damping;     // same pattern
  double energy = 0;
};
// The matrices are left unset without `with_matrices`.
AxialLink axial_link(const Eigen::Vector3d& xa, const Eigen::Vector3d& xb,
                     const Eigen::Vector3d& va, const Eigen::Vector3d& vb, double spring,
                     double damper, double rest_length, bool with_matrices = true);

// Bending joint at node 1 between links (0,1) and (1,2) (seed eq. 10, 11, 13, 15). The energy is
// (spring/2) phi^2 with phi the angle between the links: the moment spring * phi is the elastica
// curvature moment EI kappa with kappa = phi / l0; the seed's tan(phi) agrees to first order but
// is not conservative at large angles. The dashpot acts on the relative angular velocity of the
// two links, which stays smooth through the straight shape.
struct BendingJoint {
  Eigen::Vector3d force[3];
  Eigen::Matrix3d stiffness[3][3];
  Eigen::Matrix3d damping[3][3];
  double energy = 0;
};
void bending_joint(const Eigen::Vector3d x[3], const Eigen::Vector3d v[3], double spring,
                   double damper, bool with_matrices, BendingJoint& out);

// Quadratic drag on the velocity of the fluid relative to the node, normal to the local tangent
// (seed eq. 16 with |u_n| u_n): factor = 0.5 rho C_D b ds.
struct NodeDrag {
  Eigen::Vector3d force;
  Eigen::Matrix3d damping;            // minus d force / d node velocity (unset without matrices)
  Eigen::Matrix3d tangent_stiffness;  // minus d force / d tangent, when asked (else zero)
};
NodeDrag node_drag(const Eigen::Vector3d& tangent, const Eigen::Vector3d& ambient,
                   const Eigen::Vector3d& velocity, double factor,
                   bool with_tangent_stiffness = false, bool with_matrices = true);

}  // namespace cosim::vegetation
