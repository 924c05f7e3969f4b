// Bed contact of the plants: a frictionless unilateral penalty constraint keeping every free node
// above the bed plane. With the gap g = n . x - h (n the bed normal, against gravity; h the bed
// plane plus half the plant's thickness, so that a lying plant rests on its face), the normal
// force is the penalty spring-dashpot
//   N = max(0, -k g - c n . v)   for g < 0,   N = 0 otherwise,
// acting along n: the penalty regularisation of the Signorini condition g >= 0, N >= 0, N g = 0
// (P. Wriggers, Computational Contact Mechanics, 2nd ed., Springer 2006, ch. 2: the penalty
// method, N = eps_N <-g>), with the linear dashpot of the discrete-element normal contact
// (P. A. Cundall and O. D. L. Strack, Geotechnique 29 (1979) 47-65) and no adhesion (N >= 0).
// It is one more internal force of the implicit Newmark step: the residual m a - F takes it at
// the trial position, and the Jacobian its tangent k n n^T (and c n n^T) for the nodes in
// contact there, so the Newton iteration of a sub-step is exact for a node that stays in contact.
#include <algorithm>
#include <cmath>

#include "cosim/vegetation_beam/plant_field.hpp"

namespace cosim::vegetation {

void PlantField::setup_bed_contact(Plant& plant, const PlantSpec& spec, double link_mass) const {
  const BeamParameters& p = parameters_;
  if (!p.bed_contact) return;
  // The bed is normal to gravity; without gravity it is normal to the plant's direction.
  plant.bed_normal = p.gravity.norm() > 0 ? (-p.gravity.normalized()).eval() : spec.direction;
  plant.bed_height = plant.bed_normal.dot(spec.base) - p.bed_below_base + 0.5 * spec.thickness;
  // The spring must be resolved by the sub-step: the trapezoidal rule conserves energy only for
  // forces that are smooth over a step, and a node switching in and out of an unresolved stiff
  // contact gains energy (measured: a blade pressed flat at safety_factor 10 with k = EA / l0
  // kept its tip chattering at 5 m/s). The default is EA / l0, softened by safety_factor^2
  // above 1 so that its period sqrt(m / k) stays at or above the sub-step; a given stiffness
  // limits the sub-step instead (step_limit).
  const double softening = std::max(1.0, p.safety_factor);
  plant.bed_spring =
      p.bed_stiffness > 0 ? p.bed_stiffness : plant.axial_spring / (softening * softening);
  // A node against a fixed plane: critical damping 2 sqrt(k m) with the link's mass.
  plant.bed_damper = p.contact_damping_ratio * 2 * std::sqrt(plant.bed_spring * link_mass);
}

void PlantField::add_bed_contact(const Plant& plant, const std::vector<Eigen::Vector3d>& x,
                                 const std::vector<Eigen::Vector3d>& v,
                                 std::vector<Eigen::Vector3d>& force, BandedMatrix* jacobian,
                                 double stiffness_weight, double damping_weight) const {
  if (plant.bed_spring <= 0) return;
  const Eigen::Vector3d& n = plant.bed_normal;
  const Eigen::Matrix3d along = n * n.transpose();
  for (int i = 1; i <= plant.links; ++i) {
    const int k = plant.first + i;
    const double gap = n.dot(x[k]) - plant.bed_height;
    if (!(gap < 0)) continue;
    const double normal = -plant.bed_spring * gap - plant.bed_damper * n.dot(v[k]);
    if (!(normal > 0)) continue;  // a node leaving the bed faster than the spring pushes
    force[k] += normal * n;
    if (jacobian == nullptr) continue;
    jacobian->add_blocks(i - 1, i - 1, along, plant.bed_spring * stiffness_weight, along,
                         plant.bed_damper * damping_weight);
  }
}

double PlantField::bed_energy() const {
  double energy = 0;
  for (const Plant& plant : plants_) {
    if (plant.bed_spring <= 0) continue;
    for (int i = 1; i <= plant.links; ++i) {
      const double gap = plant.bed_normal.dot(positions_[plant.first + i]) - plant.bed_height;
      if (gap < 0) energy += 0.5 * plant.bed_spring * gap * gap;
    }
  }
  return energy;
}

}  // namespace cosim::vegetation
