// Hydrostatic background of the pressure gradient (issue 16). The particle gradient operators
// (pressure_gradient.hpp) err in proportion to how much the pressure varies within their radius;
// in slow free-surface flows most of that variation is hydrostatic (rho g = 9.8 kPa/m, hundreds
// of times the streamwise drive of a river reach), and the minimum form's non-conservation of
// that part is what leaves the rigid-canopy momentum balance open. Splitting p = p_b + q with a
// smooth background p_b whose gradient is known exactly, the particle operator sees only q and
// the background's gradient is added analytically: grad p = grad p_b(x_i) + <grad q>_i. The
// split is exact in the continuum; it changes only which part the discrete operator carries.
//
// p_b = rho |g_up| f(eta(x_t) - h), h the height along -g's dominant axis, eta the free
// surface above x_t: half a spacing above the top particle of the lowest layer of water in each
// column bin (width l0; water_level() reads the surface the same way). Layers are read off the
// bin and its neighbours (3 l0 wide; one bin of disordered water has gaps of 4 l0 inside it) and
// end at a gap of more than 3 l0, so a nappe, jet or splash over air is not part of the column
// below it and has no background of its own. eta is averaged over the non-empty bins within two
// bins either way and interpolated (bi)linearly between bin centres. f fades the background in
// over the depth delta below the surface (f = d^2 / (2 delta) above delta, d - delta / 2 below,
// so f' = min(d / delta, 1)): in that layer the operator still carries the particles' weight, as
// without a background. With blend_fade, f = d (p_b linear) and S is scaled by min(d / delta, 1)
// instead: the same handover, but the operator never sees the taper's curvature. S is the trust in
// the column, 0 to 1, interpolated as eta: within reach of the operator from the smoothing window
// (2 + delta / l0 bins either way) the surface heights and the bed heights (the lowest water of
// each column) must each span at most delta for 1, and S is 0 from 2 delta on (a steep face, a
// surge front, a brink, a nappe, a crest or the top of a partition: the column height says little
// of the pressure there), a smoothstep between; S is also 0 within reach of water whose lowest
// particle has no wall within the gap below or beside it (a nappe past a brink, a falling jet), and
// within three depths of the water over such a column or over the higher side of a step in the bed
// (the flow over a brink or a crest curves a few depths upstream of it), where that is farther.
// Bins farther than two from any water have no background. Periodic channels wrap the bins (with
// the period's drop). grad p_b is the exact gradient of this field.
//
// The fluid step weighs two whole estimates by S: S (<grad q>_i + grad p_b) + (1 - S) <grad p>_i,
// so that no gradient of S (rho g times the whole depth over a few bins) enters the force, and
// untrusted water steps exactly as without a background.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "cosim/fluid_mps/parameters.hpp"

namespace cosim::mps {

struct BackgroundInput {
  int dimension = 2;
  Eigen::Vector3d gravity = Eigen::Vector3d::Zero();  // [m/s^2]
  double density = 1000.0;                            // [kg/m^3]
  double particle_spacing = 0.0;                      // l0 [m]: the column bin width
  // delta [m]; 0: no fade-in, S = 1 (the step passes r_e of the gradient)
  double taper_depth = 0.0;
  // The fade-in's own depth delta [m] where it differs from taper_depth (0: taper_depth), and
  // its form (MpsParameters::BackgroundFade): blend keeps p_b linear and scales S instead.
  double fade_depth = 0.0;
  bool blend_fade = false;
  const std::vector<Eigen::Vector3d>* positions = nullptr;
  const std::vector<ParticleKind>* kinds = nullptr;
  const PeriodicBoundary* periodic = nullptr;  // nullptr: none
};

// The background at every fluid and wall particle (zero at the others).
struct BackgroundField {
  std::vector<double> pressure;           // p_b [Pa]
  std::vector<Eigen::Vector3d> gradient;  // grad p_b [Pa/m]
  std::vector<double> trust;              // S [-]
  std::vector<double> fade;               // f' = min(d / delta, 1), 0 without a column [-]
                                          // (blend: 1, the fade is in S)
};

void hydrostatic_background(const BackgroundInput& in, BackgroundField& out);

}  // namespace cosim::mps
