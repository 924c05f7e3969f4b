// Pressure-gradient models of the MPS correction stage and particle shifting (issue 16). The
// fluid step (fluid_step.cpp) calls these on its pair list; tests call them on any particle set,
// so the tested operators are the operators that run.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "cosim/fluid_mps/neighbour_grid.hpp"
#include "cosim/fluid_mps/parameters.hpp"

namespace cosim::mps {

// What the models read: particles at r*, their kinds and pressures, the pair list with the
// distances at r* and the gradient radius. Dummy particles carry no pressure and are left out of
// every sum. The step passes its near-pair list (fluid_pairs.cpp), whose row i ends at
// row_end[i] rather than at the next row's offset; without row_end a row ends at offset[i + 1].
struct GradientInput {
  int dimension = 2;
  double radius = 0.0;  // r_e of the gradient [m]
  double n0 = 0.0;      // number density of the full lattice at that radius
  const NeighbourList* neighbours = nullptr;
  const std::vector<std::int64_t>* row_end = nullptr;
  const std::vector<Eigen::Vector3d>* positions = nullptr;
  const std::vector<ParticleKind>* kinds = nullptr;
  const std::vector<double>* pressure = nullptr;
  const PeriodicBoundary* periodic = nullptr;
  // Pressure unknown of each particle, -1 on the free surface (corrected_interior only).
  const std::vector<int>* unknown = nullptr;
  // corrected_blended: the surface threshold beta (the blend weight is 0 at n_i = beta n0) and
  // the solid fraction phi of each particle (a neighbourhood among solids is full at
  // (1 - phi) n0; nullptr: no solids).
  double surface_threshold = 0.97;
  const std::vector<double>* solid_fraction = nullptr;

  std::int64_t begin(int i) const { return neighbours->offset[i]; }
  std::int64_t end(int i) const { return row_end ? (*row_end)[i] : neighbours->offset[i + 1]; }
};

// The pair sums S_i of the pressure gradient <grad p>_i = d/n0 S_i [Pa/m] at every fluid
// particle (zero elsewhere) by `form`, and the share of the wall particles in them (`wall`), which
// the step books as the walls' pressure force on the fluid. The corrected form returns n0/d C_i
// times its sum, so the caller scales every form alike (and the minimum form keeps the bits of
// the sum it always had). `minimum` is the work array of p^_i (smallest pressure around i).
// With `evaluate`, only the fluid particles with evaluate[i] != 0 are evaluated (the others get
// zero sums): the step weighs two estimates per particle and needs each only where it counts.
void pressure_gradients(MpsParameters::GradientForm form, const GradientInput& in,
                        std::vector<Eigen::Vector3d>& gradient, std::vector<Eigen::Vector3d>& wall,
                        std::vector<double>& minimum, const std::vector<char>* evaluate = nullptr);

// background_repulsion: full (issue 16). The forms with a neighbourhood minimum split as
// sum_j (x_j - x_i) F_ij + (x_i - x^_i) sum_j F_ij (F_ij = r_ij w_ij / |r_ij|^2): a Taylor
// difference and the repulsion that subtracting x^_i adds (Koshizuka & Oka 1996). Run on
// q = p - p_b (in.pressure) the repulsion is q's, near zero in water at rest; on the whole
// pressure it is of order rho g r_e, and it pushes a particle moved off its place back towards
// the middle of its neighbours: the stiffness that lets a resting lattice settle. This adds
// f'_i ((p_i - p^_i) - (q_i - q^_i)) M_i sum_j F_ij to the sums `pressure_gradients` gave on q
// (`dynamic_minimum` its q^_i, M_i the matrix the form applies there, f'_i = `fade`, the
// background's own fade-in below the surface, BackgroundField), and the walls' share to `wall`,
// at the fluid particles `evaluate` marks; the Taylor part stays on q. The fade keeps the
// repulsion where the exact grad p_b already carries the weight and the neighbourhood is one-
// sided (near the surface sum F points down: the repulsion would lift the top layer a second
// time; still water at l0 = 1 cm reads +2.4 % at 0.05 m without the fade, +1.2 % with it).
// Nothing for the symmetric forms, which have no minimum. `full_minimum` is the work array of
// p^_i, as `minimum` of pressure_gradients.
void add_full_pressure_repulsion(MpsParameters::GradientForm form, const GradientInput& in,
                                 const std::vector<double>& dynamic_minimum,
                                 const std::vector<double>& full_pressure,
                                 const std::vector<double>& fade, const std::vector<char>* evaluate,
                                 std::vector<Eigen::Vector3d>& gradient,
                                 std::vector<Eigen::Vector3d>& wall,
                                 std::vector<double>& full_minimum);

// background_replaces: layer_mean (issue 16, ninth round). Under the background the operator's
// Taylor part on p_b, T_i = sum (p_b,j - p_b,i) F_ij with the form's matrix, is replaced by the
// exact grad p_b. T_i's dependence on where the particles sit is the lattice's stiffness (a
// particle pushed out of place meets a changed sum); only its mean over the particles of the same
// depth is the operator's bias. This adds back T_i - <T>_layer at every fluid particle
// `evaluate` marks, layers `layer_width` [Pa] of p_b thick: the bias stays replaced, the
// stiffness is the default operator's again, and each layer's added forces sum to zero (no net
// momentum). `order` lists the particles in the order their layer sums are taken; `taylor` is a
// work array.
void keep_layer_deviation(MpsParameters::GradientForm form, const GradientInput& in,
                          const std::vector<double>& background, double layer_width,
                          const std::vector<char>& evaluate, const std::vector<int>& order,
                          std::vector<Eigen::Vector3d>& taylor,
                          std::vector<Eigen::Vector3d>& gradient);

// The correction matrix of Khayyer & Gotoh (2011), Appl. Ocean Res. 33: C_i = [sum_j w_ij
// r_ij (x) r_ij / |r_ij|^2]^-1 over the non-dummy neighbours (the D x D block; the rest of the
// 3 x 3 matrix is zero in 2D). It is d/n0 times the identity on a full lattice. Where the
// neighbourhood is too thin to invert (a splash particle with one or two neighbours) it falls
// back to d/n0 I, the uncorrected operator.
Eigen::Matrix3d correction_matrix(const GradientInput& in, int i);

// Weight w_i of the correction matrix in corrected_blended: t = (n_i / ((1 - phi_i) n0) - beta)
// / (1 - beta) clamped to [0, 1], w_i = t^2 (3 - 2 t) (a smoothstep, flat at both ends), with n_i
// = sum_j w(r_ij) over every neighbour within the gradient radius but inactive ones (walls and
// dummies count: a wall completes the neighbourhood, only a free surface leaves it empty). n_i is
// the trace of the moment matrix, so it measures how full the neighbourhood is regardless of
// how its particles are arranged. 0 on a flat free surface (n_i about 0.6 n0), 1 in the interior.
double correction_weight(const GradientInput& in, int i);

// The corrected gradient of a field with reference values: C_i sum_j (phi_j - reference_i)
// r_ij / |r_ij|^2 w_ij. With reference_i = phi_i it recovers the gradient of a linear field
// exactly on any arrangement whose C_i exists (Khayyer & Gotoh 2011; the first-order
// least-squares MPS of Tamai & Koshizuka 2014, Comp. Part. Mech. 1, with the MPS weight).
std::vector<Eigen::Vector3d> corrected_gradient(const GradientInput& in,
                                                const std::vector<double>& field,
                                                const std::vector<double>& reference);

// Fickian particle shifting (Lind, Xu, Stansby & Rogers 2012, J. Comput. Phys. 231; after Xu,
// Stansby & Laurence 2009): dr_i = -D grad C_i with D = A l0 |u_i| dt and grad C_i the MPS
// gradient of the particle concentration, d/n0 sum_j r_ij / |r_ij|^2 w_ij over every neighbour
// (walls and dummies count). It moves particles from crowded to sparse places. With `taylor`
// false the velocities are left as they are, so the fluid's momentum is untouched; with it each
// shifted particle takes u_i + J_i dr_i, J_i = sum_j w_ij (u_j - u_i) r_ij^T / |r_ij|^2 C_i (the
// corrected gradient of the velocity over the non-dummy neighbours, exact for a linear field;
// all J_i from the velocities before any change). With `tangential_at_walls` the shift loses its
// component along n_w, the direction of the wall and dummy neighbours' share of grad C_i (a
// particle beside a wall slides along it). Fluid particles on the free surface
// (pressure_unknown[i] < 0: no pressure unknown) or with such a particle within the radius are
// not shifted (Lind et al. shift those along the surface only; here they keep their place). Each
// shift is capped at `max_shift` [m]. Returns the largest shift [m].
struct ShiftingOptions {
  double coefficient = 2.0;       // A
  double dt = 0.0;                // [s]
  double particle_spacing = 0.0;  // l0 [m]
  double max_shift = 0.0;         // [m]
  bool taylor = false;
  bool tangential_at_walls = false;
};
double shift_particles(const GradientInput& in, std::vector<Eigen::Vector3d>& velocities,
                       const std::vector<int>& pressure_unknown, const ShiftingOptions& options,
                       std::vector<Eigen::Vector3d>& positions_out);

}  // namespace cosim::mps
